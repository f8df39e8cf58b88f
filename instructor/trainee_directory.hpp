#pragma once

// Who is training: every trainee station seen on rise/<id>/panel_state,
// robot_state and task_status, with what the instructor wants at a glance.
// Fed by rise-instructor list (and the web console) from LCM; pure.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "rise_msgs/PanelState.hpp"
#include "rise_msgs/RobotState.hpp"
#include "rise_msgs/TaskStatus.hpp"

namespace rise::instructor {

/// A process heard publishing one of a trainee's channels.
struct SeenPublisher {
  std::string what;          ///< "panel_state", "robot_state", "task_status"
  rise_msgs::Publisher publisher;
  int64_t last_seen_us = 0;  ///< wall clock of its newest message there
};

struct TraineeRow {
  std::string id;
  int64_t last_seen_us = 0;  ///< wall clock of the newest message
  std::optional<rise_msgs::PanelState> panel;
  std::optional<rise_msgs::RobotState> robot;
  std::optional<rise_msgs::TaskStatus> task;
  std::vector<SeenPublisher> publishers;  ///< every process heard, per channel

  /// The channels ("panel_state", ...) on which more than one process was
  /// heard within `window_us` before now_us: two publishers on one station.
  std::vector<std::string> duplicated(int64_t now_us, int64_t window_us = 2'000'000) const;
  /// Whether nothing of it came within `after_us` before now_us (the clock of
  /// on_message's now_us): a station lost, its link cut or its programs
  /// stopped (the web console watches this live: instructor/trainee_links.hpp).
  bool lost(int64_t now_us, int64_t after_us = 500'000) const { return now_us - last_seen_us > after_us; }
};

class TraineeDirectory {
 public:
  /// Takes one message from `channel` (rise/<id>/<what>); false for a
  /// channel that is not a trainee's panel_state/robot_state/task_status.
  /// The channel's id names the trainee, whatever the message claims.
  bool on_message(const std::string& channel, const void* data, int size, int64_t now_us);
  std::vector<TraineeRow> rows() const;

 private:
  std::map<std::string, TraineeRow> rows_;
};

}  // namespace rise::instructor
