#include "process/chain_monitor.hpp"

#include "msgs/channels.hpp"
#include "msgs/lcm_decode.hpp"
#include "msgs/panel_state_controls.hpp"
#include "msgs/publisher_session.hpp"

#include <poll.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace rise::process {
namespace {

double yaw_deg(const rise_msgs::RobotState& r) {
  const double w = r.orientation_wxyz[0], x = r.orientation_wxyz[1], y = r.orientation_wxyz[2],
               z = r.orientation_wxyz[3];
  return std::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)) * 180.0 / M_PI;
}

bool at_standstill(const rise_msgs::RobotState& r) {
  return std::hypot(r.linear_velocity_mps[0], r.linear_velocity_mps[1]) < kStandstillSpeedMps &&
         std::fabs(r.angular_velocity_radps[2]) < kStandstillTurnRadps;
}
}  // namespace

ChainMonitor::ChainMonitor(const std::string& lcm_url, const std::string& trainee_id) : lcm_(lcm_url) {
  good_ = lcm_.good();
  if (!good_) return;
  auto* p = msgs::subscribe<&ChainMonitor::on_panel>(lcm_, msgs::panel_state_channel(trainee_id), this);
  auto* r = msgs::subscribe<&ChainMonitor::on_robot>(lcm_, msgs::robot_state_channel(trainee_id), this);
  // Every message counts for the measurements: a queue deep enough for a
  // second of traffic at 100 + 50 Hz.
  p->setQueueCapacity(200);
  r->setQueueCapacity(100);
  thread_ = std::thread([this] { loop(); });
}

ChainMonitor::~ChainMonitor() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
}

void ChainMonitor::loop() {
  while (running_) {
    pollfd pfd{lcm_.getFileno(), POLLIN, 0};
    if (::poll(&pfd, 1, 20) > 0) lcm_.handle();
  }
}

void ChainMonitor::accept_only(std::vector<int32_t> pids) {
  std::lock_guard lock(mutex_);
  accepted_pids_ = std::move(pids);
  host_ = msgs::this_publisher().host;
}

bool ChainMonitor::accepted(const rise_msgs::Publisher& p) {
  if (accepted_pids_.empty()) return true;
  if (p.host == host_ &&
      std::find(accepted_pids_.begin(), accepted_pids_.end(), p.pid) != accepted_pids_.end())
    return true;
  ++view_.foreign_count;
  view_.foreign = p;
  return false;
}

void ChainMonitor::on_panel(const lcm::ReceiveBuffer*, const std::string&,
                            const rise_msgs::PanelState* m) {
  std::lock_guard lock(mutex_);
  if (!accepted(m->publisher)) return;
  view_.panel = *m;
  view_.have_panel = true;
  ++view_.panel_count;
  const bool moving = view_.speed_mps > kMovingSpeedMps;

  if (deadman_was_held_ && !m->deadman && !m->failsafe && !view_.deadman_stop.triggered && moving) {
    view_.deadman_stop.triggered = true;
    view_.deadman_stop.trigger_utime = m->utime;
    view_.deadman_stop.speed_at_trigger_mps = view_.speed_mps;
  }
  deadman_was_held_ = m->deadman && !m->failsafe;

  bool source_lost = false;
  int64_t last_frame_utime = m->utime;
  for (const auto& s : m->sources)
    if (!s.connected || s.stale) {
      source_lost = true;
      if (s.last_frame_age_us >= 0) last_frame_utime = std::min(last_frame_utime, m->utime - s.last_frame_age_us);
    }
  if (source_lost && was_connected_ok_ && !view_.loss_stop.triggered && moving) {
    view_.loss_stop.triggered = true;
    // The loss happened when the last valid frame arrived, not when the
    // bridge noticed: measure from there.
    view_.loss_stop.trigger_utime = last_frame_utime;
    view_.loss_stop.speed_at_trigger_mps = view_.speed_mps;
    view_.loss_causes = msgs::FailsafeCauses{m->failsafe_causes};
    view_.loss_reason = m->failsafe_reason;
  }
  was_connected_ok_ = !source_lost;
  was_failsafe_ = m->failsafe;
  changed_.notify_all();
}

void ChainMonitor::on_robot(const lcm::ReceiveBuffer*, const std::string&,
                            const rise_msgs::RobotState* m) {
  std::lock_guard lock(mutex_);
  if (!accepted(m->publisher)) return;
  if (view_.have_robot)
    view_.distance_m += std::hypot(m->position_m[0] - view_.robot.position_m[0],
                                   m->position_m[1] - view_.robot.position_m[1]);
  view_.robot = *m;
  view_.have_robot = true;
  ++view_.robot_count;
  view_.speed_mps = std::hypot(m->linear_velocity_mps[0], m->linear_velocity_mps[1]);
  for (StopMeasurement* s : {&view_.deadman_stop, &view_.loss_stop})
    if (s->triggered && !s->stopped && m->utime >= s->trigger_utime && at_standstill(*m)) {
      s->stopped = true;
      s->stop_utime = m->utime;
    }
  changed_.notify_all();
}

ChainView ChainMonitor::view() const {
  std::lock_guard lock(mutex_);
  return view_;
}

bool ChainMonitor::wait_until(const std::function<bool(const ChainView&)>& pred, int timeout_ms) const {
  std::unique_lock lock(mutex_);
  return changed_.wait_for(lock, std::chrono::milliseconds(timeout_ms), [&] { return pred(view_); });
}

void ChainMonitor::rearm() {
  std::lock_guard lock(mutex_);
  view_.deadman_stop = {};
  view_.loss_stop = {};
}

std::string ChainMonitor::live_line() const {
  std::lock_guard lock(mutex_);
  char buf[320];
  const auto& p = view_.panel;
  const auto& r = view_.robot;
  std::snprintf(buf, sizeof buf,
                "panel %-8s deadman=%d drive=(%+.2f,%+.2f) speed=%-6s | robot x=%+6.2f y=%+6.2f "
                "yaw=%+7.1f° v=%.2f m/s %s",
                !view_.have_panel ? "waiting" : p.failsafe ? "FAILSAFE" : "ok", p.deadman ? 1 : 0,
                static_cast<double>(msgs::find_axis(p, "drive_x").value_or(0.0f)),
                static_cast<double>(msgs::find_axis(p, "drive_y").value_or(0.0f)),
                msgs::find_switch_label(p, "speed").value_or("-").c_str(), r.position_m[0], r.position_m[1],
                view_.have_robot ? yaw_deg(r) : 0.0, view_.speed_mps,
                view_.have_robot && !r.motors_enabled ? ("[stopped: " + r.stop_reason + "]").c_str() : "");
  std::string line = buf;
  if (view_.have_panel && p.failsafe) line += " (" + p.failsafe_reason + ")";
  return line;
}

}  // namespace rise::process
