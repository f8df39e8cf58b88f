#include "hil/bridge.hpp"

#include <algorithm>
#include <chrono>
#include <string>
#include <utility>

#include "hil/can_source.hpp"
#include "hil/canopen_source.hpp"
#include "hil/j1939_source.hpp"
#include "msgs/clock.hpp"

namespace rise::hil {
namespace {

std::vector<std::unique_ptr<SourceTransport>> can_sources(const panels::PanelDefinition& definition,
                                                          std::vector<std::unique_ptr<io::CanBus>> buses) {
  std::vector<std::unique_ptr<SourceTransport>> sources;
  for (std::size_t i = 0; i < buses.size(); ++i) {
    std::unique_ptr<SourceTransport> source;
    if (buses[i] && definition.sources[i].is_canopen())
      source = std::make_unique<CanopenSource>(std::move(buses[i]), definition, i);
    else if (buses[i] && definition.sources[i].is_j1939())
      source = std::make_unique<J1939Source>(std::move(buses[i]), definition, i);
    else if (buses[i])
      source = std::make_unique<CanSource>(std::move(buses[i]), definition, i);
    sources.push_back(std::move(source));
  }
  return sources;
}

// The source is down, for `reason`; published at once when `now`.
void mark_down(SourcePanel& panel, const std::string& reason, bool now) {
  panel.update([&](PanelMapper& mapper, int64_t now_us) {
    mapper.on_connection(panel.source(), false, now_us, reason);
    return now;
  });
}

// What one source's loop keeps while its transport is closed.
struct Reconnect {
  ConnectionPolicy policy;
  ReopenSchedule schedule;
  std::string down_reason;  // the transport's error, read when it fails (not every loop)
};

// A closed transport: reopened when due, its source down while it stays
// closed (ConnectionPolicy says from when). True when it is open now.
bool reconnect(SourcePanel& panel, SourceTransport& transport, Reconnect& r, int64_t now_us) {
  if (r.policy.closed_is_down) mark_down(panel, r.down_reason, false);
  if (r.schedule.due(now_us)) {
    const bool opened = transport.reopen(panel) == io::IoStatus::Ok;
    if (!opened) r.down_reason = transport.last_error();
    r.schedule.attempted(now_us, opened);
  }
  if (transport.is_open()) return true;
  if (!r.policy.closed_is_down) mark_down(panel, r.down_reason, false);
  if (transport.wait_while_closed(5)) r.schedule.arrived(msgs::monotonic_us());
  return false;
}
}  // namespace

Bridge::Bridge(panels::PanelDefinition definition, std::vector<std::unique_ptr<io::CanBus>> buses,
               PublishFn publish, BridgeSettings settings)
    : Bridge(definition, can_sources(definition, std::move(buses)), std::move(publish), settings) {}

Bridge::Bridge(panels::PanelDefinition definition, std::vector<std::unique_ptr<SourceTransport>> transports,
               PublishFn publish, BridgeSettings settings)
    : panel_(std::move(definition)),
      transports_(std::move(transports)),
      publish_(std::move(publish)),
      settings_(settings) {}

Bridge::~Bridge() { stop(); }

void Bridge::start() {
  if (running_.exchange(true)) return;
  for (std::size_t i = 0; i < transports_.size(); ++i)
    if (transports_[i]) threads_.emplace_back([this, i] { source_loop(i); });
  threads_.emplace_back([this] { publish_loop(); });
}

void Bridge::stop() {
  if (!running_.exchange(false)) return;
  panel_.wake.notify_all();
  for (auto& t : threads_) t.join();
  threads_.clear();
}

void Bridge::set_feedback(FeedbackRequest request) {
  std::lock_guard lock(panel_.mutex);
  feedback_ = std::move(request);
  ++feedback_version_;
}

PanelSnapshot Bridge::snapshot() const {
  std::lock_guard lock(panel_.mutex);
  return panel_.mapper.evaluate(msgs::monotonic_us());
}

std::string Bridge::inject_input_fault(InputFault fault) {
  std::string error;
  {
    std::lock_guard lock(panel_.mutex);
    error = panel_.mapper.inject_input_fault(std::move(fault));
    panel_.changed = true;
  }
  panel_.wake.notify_all();
  return error;
}

std::size_t Bridge::clear_input_faults(const std::string& id) {
  std::size_t n;
  {
    std::lock_guard lock(panel_.mutex);
    n = panel_.mapper.clear_input_faults(id, msgs::monotonic_us());
    panel_.changed = true;
  }
  panel_.wake.notify_all();
  return n;
}

std::vector<std::string> Bridge::take_notes() {
  std::lock_guard lock(panel_.mutex);
  return std::exchange(panel_.notes, {});
}

Bridge::FeedbackState Bridge::feedback_state(int64_t now_us) {
  std::lock_guard lock(panel_.mutex);
  return {panel_.mapper.evaluate(now_us), feedback_, feedback_version_};
}

void Bridge::source_loop(std::size_t source) {
  SourceTransport& transport = *transports_[source];
  SourcePanel panel(panel_, source);
  const ConnectionPolicy policy = transport.connection_policy();
  Reconnect reconnecting{policy,
                         policy.enumerate ? ReopenSchedule::enumeration(settings_.hid_enumerate_ms)
                                          : ReopenSchedule::back_off(settings_.reopen_min_ms, settings_.reopen_max_ms),
                         {}};
  if (!policy.unseen_arrivals.empty())
    panel.note(panel.definition().sources[source].name + ": " + policy.unseen_arrivals + ": enumerating every " +
               std::to_string(settings_.hid_enumerate_ms) + " ms");
  FeedbackSchedule feedback(transport.feedback_policy(), settings_.feedback_period_ms);

  while (running_) {
    const int64_t now = msgs::monotonic_us();
    const bool was_closed = !transport.is_open();
    if (was_closed && !reconnect(panel, transport, reconnecting, now)) continue;
    if (was_closed) feedback.forget();  // reopened: what the device shows is unknown
    if (was_closed || policy.up_while_open)
      panel.update([&](PanelMapper& mapper, int64_t) {
        mapper.on_connection(source, true, now);
        return false;
      });
    io::IoStatus status = transport.receive(panel, 5);
    if (status != io::IoStatus::Disconnected && transport.is_open() && transport.shows_feedback())
      status = write_feedback(panel, transport, feedback, status == io::IoStatus::Ok);
    if (status == io::IoStatus::Disconnected) {
      // A loss is published now, not at the next tick.
      reconnecting.down_reason = transport.last_error();
      mark_down(panel, reconnecting.down_reason, true);
    }
  }
}

io::IoStatus Bridge::write_feedback(SourcePanel& panel, SourceTransport& transport, FeedbackSchedule& schedule,
                                    bool polled) {
  const int64_t now = msgs::monotonic_us();
  if (!schedule.due(now, feedback_version_, polled)) return io::IoStatus::Ok;
  const FeedbackState state = feedback_state(now);
  const io::IoStatus status = transport.send_feedback(panel, state.request, state.snapshot, schedule.resend(now));
  schedule.built(now, state.version, status == io::IoStatus::Ok);
  return status;
}

void Bridge::publish_loop() {
  using Clock = std::chrono::steady_clock;
  const auto period = std::chrono::microseconds(panel_.mapper.definition().publish_period_us());
  const auto gap = std::chrono::microseconds(settings_.min_change_gap_us);
  auto next_tick = Clock::now();
  auto last_publish = Clock::now() - gap;
  while (running_) {
    PanelSnapshot snap;
    {
      std::unique_lock lock(panel_.mutex);
      // Publish on the tick, or as soon as a control changed — but not
      // sooner than `gap` after the last message, so a chattering console
      // cannot flood the network. A change inside the gap is published when
      // the gap ends, not at the next tick.
      while (running_) {
        const auto now = Clock::now();
        if (now >= next_tick || (panel_.changed && now - last_publish >= gap)) break;
        const auto deadline = panel_.changed ? std::min(next_tick, last_publish + gap) : next_tick;
        panel_.wake.wait_until(lock, deadline);
      }
      if (!running_) break;
      panel_.changed = false;
      snap = panel_.mapper.evaluate(msgs::monotonic_us());
    }
    const auto now = Clock::now();
    if (now >= next_tick) {
      next_tick += period;
      if (next_tick < now) next_tick = now + period;  // overrun: skip, do not burst
    }
    last_publish = now;
    publish_(snap);
  }
}
}  // namespace rise::hil
