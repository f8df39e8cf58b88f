#include "instructor/virtual_panels.hpp"

#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <utility>
#include <vector>

#include "hil/panel_state_message.hpp"
#include "msgs/channels.hpp"
#include "msgs/clock.hpp"
#include "rise_msgs/PanelState.hpp"

namespace rise::instructor {

VirtualPanels::VirtualPanels(panels::PanelDefinition console, uint32_t timeout_ms,
                             const std::optional<msgs::InstructorKey>& key, lcm::LCM& lcm,
                             const msgs::PublisherWatch& publishers)
    : console_(std::move(console)), timeout_ms_(timeout_ms), lcm_(lcm), publishers_(publishers) {
  (void)virtual_definition(console_, timeout_ms_);  // fails here, not on the first page
  if (key) verifier_ = std::make_unique<msgs::CommandVerifier>(*key);
}

VirtualPanels::~VirtualPanels() { stop(); }

void VirtualPanels::start() {
  publishing_ = true;
  thread_ = std::thread([this] { publish_loop(); });
}

void VirtualPanels::stop() {
  publishing_ = false;
  if (thread_.joinable()) thread_.join();
}

std::optional<VirtualRefusal> VirtualPanels::update(const std::string& id, const VirtualControls& controls,
                                                    const std::string& client, const std::string& page) {
  std::lock_guard lock(mutex_);
  if (!page.empty()) {
    const auto closed = closed_page_.find(id);
    if (closed != closed_page_.end() && closed->second == page)
      return VirtualRefusal{false, true, "page '" + page + "' of trainee '" + id + "' has closed"};
  }
  auto& vp = panels_[id];
  if (!vp) {
    // One publisher per station: not beside a console's rise-hild (or another server's panel).
    for (const auto& o : publishers_.others(msgs::monotonic_us()))
      if (o.channel == msgs::panel_state_channel(id)) {
        panels_.erase(id);
        return VirtualRefusal{true, false, o.channel + " is already published by " +
                                        msgs::describe(o.publisher, msgs::wall_us()) +
                                        ": a virtual panel there would mix with it"};
      }
    vp = std::make_unique<VirtualPanel>(console_, timeout_ms_, client);
  }
  if (auto e = vp->update(controls, msgs::monotonic_us())) return VirtualRefusal{false, false, *e};
  return std::nullopt;
}

bool VirtualPanels::disconnect(const std::string& id, const std::string& page) {
  std::lock_guard lock(mutex_);
  const auto it = panels_.find(id);
  if (it == panels_.end()) return false;
  if (!page.empty()) closed_page_[id] = page;
  it->second->disconnect(msgs::monotonic_us());
  return true;
}

void VirtualPanels::on_fault_command(const std::string& trainee, const rise_msgs::FaultCommand& c) {
  std::lock_guard lock(mutex_);
  const auto it = panels_.find(trainee);
  if (it == panels_.end()) return;
  const int64_t now = msgs::monotonic_us();
  if (c.trainee_id != trainee) return it->second->note_rejected("for trainee '" + c.trainee_id + "'", now);
  if (!verifier_) return it->second->note_rejected("no instructor key on this server", now);
  const auto verdict = verifier_->check(c, msgs::wall_us());
  if (verdict != msgs::Verdict::Accepted) return it->second->note_rejected(msgs::to_string(verdict), now);
  // Other layers' faults (physics, sensors) are rise-sim's: not an error here.
  const std::string why = it->second->apply(c, now);
  (void)why;
}

bool VirtualPanels::has(const std::string& id) const {
  std::lock_guard lock(mutex_);
  return panels_.count(id) > 0;
}

std::set<std::string> VirtualPanels::ids() const {
  std::lock_guard lock(mutex_);
  std::set<std::string> out;
  for (const auto& [id, vp] : panels_) out.insert(id);
  return out;
}

void VirtualPanels::publish_loop() {
  const double hz = console_.publish_hz > 0 ? console_.publish_hz : 100.0;
  const auto period = std::chrono::microseconds(static_cast<int64_t>(1e6 / hz));
  auto next = std::chrono::steady_clock::now();
  while (publishing_) {
    next += period;
    std::this_thread::sleep_until(next);
    std::vector<std::pair<std::string, rise_msgs::PanelState>> out;
    {
      std::lock_guard lock(mutex_);
      const int64_t now = msgs::monotonic_us(), utime = msgs::wall_us();
      for (auto& [id, vp] : panels_) out.emplace_back(id, vp->state(id, now, utime));
    }
    for (auto& [id, state] : out) lcm_.publish(msgs::panel_state_channel(id), &state);
  }
}

}  // namespace rise::instructor
