#pragma once

// Watches one trainee station's LCM traffic (PanelState, RobotState) and
// measures what the demo and the chain tests report: distance driven, and
// the time from a dead-man release or a source loss to the robot's standstill.

#include <atomic>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "msgs/failsafe.hpp"
#include "rise_msgs/PanelState.hpp"
#include "rise_msgs/RobotState.hpp"

namespace rise::process {

/// Standstill: base speed below these (m/s, rad/s).
inline constexpr double kStandstillSpeedMps = 0.01;
inline constexpr double kStandstillTurnRadps = 0.02;
/// A stop is measured only when the robot was at least this fast.
inline constexpr double kMovingSpeedMps = 0.05;

struct StopMeasurement {
  bool triggered = false;
  int64_t trigger_utime = 0;    ///< wall clock µs: dead-man release published / last valid frame
  double speed_at_trigger_mps = 0.0;
  bool stopped = false;
  int64_t stop_utime = 0;       ///< first RobotState at standstill after the trigger
  double seconds() const { return static_cast<double>(stop_utime - trigger_utime) * 1e-6; }
};

struct ChainView {
  bool have_panel = false;
  bool have_robot = false;
  rise_msgs::PanelState panel;
  rise_msgs::RobotState robot;
  int64_t panel_count = 0;
  int64_t robot_count = 0;
  double distance_m = 0.0;
  double speed_mps = 0.0;
  StopMeasurement deadman_stop;
  StopMeasurement loss_stop;
  msgs::FailsafeCauses loss_causes;  ///< the panel's failsafe causes when the loss was seen
  std::string loss_reason;          ///< and their text
  /// Messages from processes that accept_only() did not name: counted,
  /// never measured; the newest such publisher.
  int64_t foreign_count = 0;
  rise_msgs::Publisher foreign;
};

class ChainMonitor {
 public:
  ChainMonitor(const std::string& lcm_url, const std::string& trainee_id);
  ~ChainMonitor();
  ChainMonitor(const ChainMonitor&) = delete;
  ChainMonitor& operator=(const ChainMonitor&) = delete;

  bool good() const { return good_; }
  ChainView view() const;
  /// Waits until pred(view) holds or timeout_ms passes; returns whether it held.
  bool wait_until(const std::function<bool(const ChainView&)>& pred, int timeout_ms) const;
  /// Arms both stop measurements again.
  void rearm();
  /// Measures only messages published by these processes (pids on this
  /// host); the rest count as ChainView::foreign_count. Empty: all.
  void accept_only(std::vector<int32_t> pids);
  /// One line: panel state and robot pose.
  std::string live_line() const;

 private:
  void on_panel(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::PanelState* m);
  void on_robot(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::RobotState* m);
  void loop();

  lcm::LCM lcm_;
  bool good_ = false;
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  ChainView view_;
  bool deadman_was_held_ = false;
  bool was_failsafe_ = true;
  bool was_connected_ok_ = false;
  std::vector<int32_t> accepted_pids_;
  std::string host_;  // this host's name: accepted pids are local
  bool accepted(const rise_msgs::Publisher& p);  // caller holds mutex_
  std::atomic<bool> running_{true};
  std::thread thread_;
};

}  // namespace rise::process
