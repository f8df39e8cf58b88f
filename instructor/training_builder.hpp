#pragma once

// The Training Builder's side of the server (/training.html): a training
// graph as the page edits it (JSON), turned into the YAML that would be saved
// and checked by the loader `rise-trainer check` uses
// (sim/training/training_graph.hpp, tasks loaded), its errors each with the
// line of that YAML, the key and the node or transition they belong to, so
// the page shows them beside what the user changed. Pure apart from reading
// the task files the graph names; never throws on the page's input.

#include <json/json.h>

#include <optional>
#include <string>
#include <vector>

#include "instructor/design_files.hpp"
#include "sim/training/training_graph.hpp"

namespace rise::instructor {

/// {training, title, comment, nodes: [{name, task, max_attempts, comment}],
///  transitions: [{from, to, if, comment}]} ("if" absent or "": always).
Json::Value training_graph_json(const sim::training::TrainingGraph& graph);

/// The page's JSON (untrusted) as a graph to write; conditions are kept as
/// text (the loader parses them, naming line and key). nullopt with *error
/// set ("nodes[2].max_attempts: expected a whole number") for a body of the
/// wrong shape.
std::optional<sim::training::TrainingGraph> training_graph_from_json(const Json::Value& body, std::string* error);


struct TrainingCheck {
  std::string yaml;  ///< what would be saved
  std::vector<BuilderError> errors;  ///< empty: rise-trainer check would say ok
};

/// Writes `graph` as it would be saved at `path` and loads that text as
/// rise-trainer check loads `path` (tasks resolved beside it). A task must be
/// a .yaml file in the training's folder (no folder in its name).
TrainingCheck check_training(const sim::training::TrainingGraph& graph, const std::string& path);

Json::Value check_json(const TrainingCheck& check);

/// The training and task files of `dir` for the page: trainings (file, name,
/// title or error), tasks (file, name, events or error), the condition
/// fields and comparisons.
Json::Value training_files_json(const std::string& dir, const std::vector<std::string>& yaml_files);

}  // namespace rise::instructor
