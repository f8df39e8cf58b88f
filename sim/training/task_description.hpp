#pragma once

// A task (the seed paper's e-Task, section 2.4): a robot, a world, a panel,
// the robot's start pose, a time limit, and the mission events that score
// points, with the conditions that end the task. Loaded from YAML
// (sim/training/examples/metro_transport.yaml; format in sim/README.md
// "Training").

#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "sim/world_description.hpp"

namespace rise::sim::training {

enum class TaskEventKind {
  ReachRegion,       ///< the robot's base enters a region (world: region_entered; task region: base inside its box)
  TimeExceeded,      ///< task time reaches after_s
  ObjectInRegion,    ///< an object's centre inside a region for hold_s
  TouchObject,       ///< a robot part starts touching the object (collision_started)
  RobotDamaged,      ///< a robot joint breaks (joint_broken)
  RobotDisabled,     ///< the robot tips over (tipped_over) or its damage reaches 1
  NeutralizeObject,  ///< the gripper on the object (contact) or within within_m of its centre for hold_s
  Collision,         ///< a penalty: per collision (collision_started) or per second of contact (collision_continues)
};
/// Stable snake_case name ("reach_region"), also the task file's `kind`.
const char* to_string(TaskEventKind kind);
std::optional<TaskEventKind> task_event_kind(const std::string& name);

/// One key an event kind takes besides name, kind, points and max_count.
struct TaskEventParam {
  const char* key;       ///< "region", "after_s", ...
  const char* type;      ///< "region" / "object" (a name), "seconds", "metres", "per" (collision|second), "names"
  bool required;
  const char* what;      ///< one line for the builder page
};
/// An event kind as the loader reads it and the executor scores it: the keys
/// it takes (any other is refused with its line), its default max_count.
struct TaskEventKindInfo {
  TaskEventKind kind;
  const char* name;
  const char* what;
  int default_max_count;  ///< 1, or 0 = no limit
  std::vector<TaskEventParam> params;
};
/// Every kind, in the order the task format documents them (the Task
/// Builder's page offers these: instructor/task_builder.hpp).
const std::vector<TaskEventKindInfo>& task_event_kinds();
const TaskEventKindInfo& task_event_kind_info(TaskEventKind kind);

/// One scored event of a task.
struct TaskEventSpec {
  std::string name;  ///< unique in the task; names it in results and end conditions
  TaskEventKind kind = TaskEventKind::ReachRegion;
  int points = 0;    ///< added each time it fires (negative: penalty)
  /// How often it may fire: 1 for goals by default, 0 = no limit (default
  /// for collision and robot_damaged).
  int max_count = 1;
  std::string region;   ///< reach_region, object_in_region
  std::string object;   ///< object_in_region, touch_object, neutralize_object
  double after_s = 0;   ///< time_exceeded
  double hold_s = 0;    ///< object_in_region, neutralize_object: continuously for this long
  /// neutralize_object: 0 = gripper contact (collision of a gripper part
  /// with the object); > 0 = the gripper finger's centre within this
  /// distance of the object's centre (a water cannon aimed at it).
  double within_m = 0;
  bool per_second = false;           ///< collision: per second of contact instead of per collision
  std::vector<std::string> except;   ///< collision: entities that do not count
  int line = 0;
  std::string comment;  ///< the `# ...` ending its line, kept by write_task_description
};

/// A task file.
struct TaskDescription {
  std::string name;
  std::string title;
  std::string file;
  std::string robot_file;    ///< resolved against the task file's folder
  std::string world_file;
  std::string panel_file;    ///< the console's panel definition ("" = none named)
  std::string console_script;  ///< a scripted console timeline for demos ("" = none)
  std::string scenario_file;   ///< a fault scenario for the instructor (rise-instructor scenario --task; "" = none)
  std::optional<RobotStart> start;  ///< default: the world's robot_start
  double time_limit_s = 300;
  std::vector<TaskEventSpec> events;
  std::vector<Region> regions;         ///< task-only regions (scored from the robot's position)
  std::vector<std::string> end_on;     ///< the task ends when any of these events fires
  std::vector<std::string> success;    ///< success = all of these fired (empty: ended by an end_on event with points >= 0)

  // As written in the file, for write_task_description (sim/training/task_writer.hpp):
  // the paths before resolving ("" = the key is absent), the comments.
  std::string robot_path, world_path, panel_path, console_script_path, scenario_path;
  std::string comment;                       ///< the comment lines before the first key
  std::vector<std::string> region_comments;  ///< one per region: the `# ...` ending its line
  std::vector<int> region_lines;             ///< one per region: its line in the file
  /// The `# ...` ending a top-level key's line ("scenario", "start", ...).
  std::map<std::string, std::string> key_comments;
};

/// Loads and checks a task file; throws std::runtime_error
/// "file:line: key: message" (unknown key, bad kind, unknown event in
/// end_on/success, missing region/object for the kind). Regions and objects
/// are checked against `world` when given.
TaskDescription load_task_description(const std::string& path);
TaskDescription parse_task_description(const std::string& text, const std::string& file);
/// Checks that the task's regions and objects exist in the world (task
/// regions count); throws "file:line: events[i].region: ...".
void check_against_world(const TaskDescription& task, const WorldDescription& world);

}  // namespace rise::sim::training
