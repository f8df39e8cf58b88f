#pragma once

// A task as the YAML that load_task_description reads: what the instructor's
// Task Builder saves. The keys in the order of the shipped tasks, paths as
// written (robot_path, ...), one flow mapping per region and per event with
// its comment, the file's opening comment first and each top-level key's
// comment kept. Reading the text back gives the same task
// (tests/training/task_writer_test.cpp checks it for every shipped task). Pure.

#include <map>
#include <string>
#include <vector>

#include "sim/training/task_description.hpp"

namespace rise::sim::training {

/// Where each entry landed in the text (1-based lines), so that an error
/// of the loader ("file:12: ...") can be pinned on the region, event or key.
struct TaskYamlLines {
  std::map<std::string, int> keys;  ///< top-level key → its line
  std::vector<int> regions;
  std::vector<int> events;
};

/// The YAML text of `task`. An event's keys are written when its kind takes
/// them (task_event_kinds()) and they differ from the loader's default;
/// after_s and the kind's required names always. Numbers with 10
/// significant digits (yaw_deg from the radians read). Never throws.
std::string write_task_description(const TaskDescription& task, TaskYamlLines* lines = nullptr);

/// `value` as the writer writes a number: shortest of %.10g.
std::string yaml_number(double value);

}  // namespace rise::sim::training
