#pragma once

// The Task Builder's side of the server (/task_builder.html): a task as the
// page edits it (JSON), turned into the YAML that would be saved
// (sim/training/task_writer.hpp) and checked as `rise-trainer check` checks a
// task (the loader, then its regions and objects against its world), each
// error with the line of that YAML and its key ("events[3].region"), so the
// page shows it beside the entry. Pure apart from reading the world file the
// task names; never throws on the page's input.

#include <json/json.h>

#include <optional>
#include <string>
#include <vector>

#include "instructor/training_builder.hpp"  // BuilderError, check_json
#include "sim/training/task_description.hpp"

namespace rise::instructor {

/// {task, title, comment, robot, world, panel, console_script, scenario (as
///  written), start: null | {x, y, yaw_deg}, time_limit_s,
///  regions: [{name, min, max, comment}],
///  events: [{name, kind, points, max_count, region, object, after_s, hold_s,
///            within_m, per, except, comment}], end_on, success, key_comments}.
Json::Value task_json(const sim::training::TaskDescription& task);

/// The page's JSON (untrusted) as a task to write. nullopt with *error set
/// ("events[2].points: expected a whole number") for a body of the wrong shape.
std::optional<sim::training::TaskDescription> task_from_json(const Json::Value& body, std::string* error);

/// The event kinds the executor scores, from the loader's own table
/// (sim::training::task_event_kinds): [{kind, what, default_max_count,
/// params: [{key, type, required, what}]}].
Json::Value task_event_kinds_json();

struct TaskCheck {
  std::string yaml;                  ///< what would be saved
  std::vector<BuilderError> errors;  ///< empty: rise-trainer check would say ok
};

/// Writes `task` as it would be saved at `path` and checks that text as
/// rise-trainer check checks a task file there (paths resolved beside it).
TaskCheck check_task(const sim::training::TaskDescription& task, const std::string& path);
Json::Value check_json(const TaskCheck& check);

/// The task files of `dir` (of `yaml_files`, those with a top-level
/// `task:`): [{file, name, title} or {file, error}], and the kinds.
Json::Value task_files_json(const std::string& dir, const std::vector<std::string>& yaml_files);

}  // namespace rise::instructor
