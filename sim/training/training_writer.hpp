#pragma once

// A training graph as the YAML that load_training_graph reads: what the
// instructor's Training Builder saves. One flow mapping per node and per
// transition, in the graph's order (transitions are tried in file order),
// each with its comment; the file's opening comment first. Reading the text
// back gives the same graph (tests/training/training_writer_test.cpp checks
// it for every shipped training file). Pure.

#include <string>
#include <vector>

#include "sim/training/training_graph.hpp"

namespace rise::sim::training {

/// Where each entry landed in the text (1-based lines), so that an error
/// of the loader ("file:12: ...") can be pinned on the node or transition.
struct TrainingYamlLines {
  std::vector<int> nodes;
  std::vector<int> transitions;
};

/// The YAML text of `graph`: training, title, nodes (name, task as written
/// — task_path, else task_file —, max_attempts), transitions (from, if: the
/// condition's text as written, to). Never throws; a condition whose text
/// does not parse is written as it is, for the loader to name.
std::string write_training_graph(const TrainingGraph& graph, TrainingYamlLines* lines = nullptr);

/// `text` as one YAML scalar: plain when that reads back as the same
/// string, else double-quoted with escapes.
std::string yaml_scalar(const std::string& text);

}  // namespace rise::sim::training
