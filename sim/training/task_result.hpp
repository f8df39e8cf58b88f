#pragma once

// What a finished task leaves (the executor's result), apart from the
// executor so that the training graph's conditions, which read it, need
// neither the executor nor the simulator (the graph's parser is fuzzed
// alone: tests/fuzz/training_graph_fuzz.cpp).

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace rise::sim::training {

/// A scored event that fired.
struct FiredEvent {
  double time_s = 0.0;  ///< task time
  std::string name;
  std::string kind;
  int points = 0;
  int score = 0;  ///< after it
  std::string detail;
};

struct TrajectoryPoint {
  double time_s = 0.0;  ///< task time
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;
};

/// What a finished (or interrupted) task leaves: what the reports show and
/// the training graph's conditions read.
struct TaskResult {
  std::string task;
  std::string title;
  std::string task_file;
  std::string world_file;
  std::string node;  ///< the training node that ran it ("" for a lone task)
  int attempt = 1;
  int score = 0;
  double time_s = 0.0;  ///< task time at the end
  double time_limit_s = 0.0;
  bool success = false;
  bool finished = false;
  std::string end_reason;  ///< "event <name>", "time limit", "simulator lost"
  double damage = 0.0;
  int collisions = 0;  ///< collision_started of the robot with anything
  std::map<std::string, int> counts;  ///< per task event: times fired (every event of the task, 0 too)
  std::vector<FiredEvent> events;
  std::vector<TrajectoryPoint> trajectory;  ///< the robot's base, every >= 0.1 s of task time
  std::map<std::string, std::vector<TrajectoryPoint>> object_tracks;  ///< the task's objects, same times

  /// A result field for the training graph: score, time_s, success (1/0),
  /// damage, collisions, attempt, or events.<name> (times fired); nullopt
  /// for an unknown name.
  std::optional<double> field(const std::string& name) const;
};

}  // namespace rise::sim::training
