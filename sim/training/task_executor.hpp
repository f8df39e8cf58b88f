#pragma once

// The task engine: fed the simulator's events and the robot's states (with
// their sim time), it fires the task's scored events, keeps score, time, the
// event log and the trajectory, and decides when the task ends. Pure: no
// clock, no I/O — rise-trainer feeds it from LCM, the tests from an
// in-process rise::sim::Simulation.

#include <array>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "sim/simulation.hpp"
#include "sim/training/task_description.hpp"
#include "sim/training/task_result.hpp"
#include "sim/world_description.hpp"

namespace rise::sim::training {

/// A simulator event as rise-sim publishes it (SimEvent.lcm) or
/// Simulation::take_events() returns it, kind by its snake_case name.
struct SimEventInput {
  double time_s = 0.0;
  std::string kind;  ///< "collision_started", "region_entered", ...
  std::string a;
  std::string b;
  std::string detail;
};
SimEventInput from_sim(const SimEvent& event);

struct ObjectSample {
  std::string name;
  std::array<double, 3> position_m{};  ///< centre, world frame
};

/// The robot (and the world's objects) at one sim time (RobotState.lcm).
struct RobotSample {
  double time_s = 0.0;
  std::array<double, 3> position_m{};
  double yaw_rad = 0.0;
  double damage = 0.0;
  std::array<double, 3> gripper_position_m{};
  std::vector<ObjectSample> objects;
};
/// Robot `robot`'s snapshot plus every object of `world` from `sim`.
RobotSample sample_of(const Simulation& sim, const WorldDescription& world, std::size_t robot = 0);

class TaskExecutor {
 public:
  /// `robot_id`: the robot's id in the events ("" accepts any robot; with
  /// several robots in the sim, parts named "<id>/<part>"). Throws
  /// std::runtime_error when the task's regions or objects are not in `world`.
  TaskExecutor(TaskDescription task, WorldDescription world, std::string robot_id = "");

  /// Feed in sim-time order. Inputs after the end are ignored. Task time
  /// counts from the first input's sim time.
  void on_sim_event(const SimEventInput& event);
  void on_state(const RobotSample& sample);

  bool finished() const { return result_.finished; }
  const TaskResult& result() const { return result_; }
  /// Events fired since the last call (for publishing them).
  std::vector<FiredEvent> take_fired();
  /// Ends the task now (the simulator died, the trainee gave up).
  void abort(const std::string& reason);
  double task_time_s() const { return result_.time_s; }
  const TaskDescription& task() const { return task_; }
  const WorldDescription& world() const { return world_; }

 private:
  void advance_time(double sim_time_s);
  void fire(const TaskEventSpec& spec, const std::string& detail);
  void finish(const std::string& reason);
  bool is_robot(const std::string& name) const;
  std::string part_of(const std::string& name) const;
  const Region* region(const std::string& name) const;

  TaskDescription task_;
  WorldDescription world_;
  std::string robot_id_;
  std::optional<double> t0_s_;
  TaskResult result_;
  std::vector<FiredEvent> fresh_;
  // Holds: the task time since when a condition held continuously, per event index.
  std::map<std::size_t, double> held_since_s_;
  // Gripper parts touching each object ("part|object").
  std::map<std::string, std::set<std::string>> gripper_contacts_;
  std::map<std::string, double> gripper_contact_since_s_;
  double last_track_s_ = -1.0;
};

}  // namespace rise::sim::training
