#include "sim/training/training_writer.hpp"

#include "panels/yaml_writer.hpp"
#include "sim/training/yaml_comments.hpp"

namespace rise::sim::training {

// Names and file paths ('/' too) plain where they read back the same.
std::string yaml_scalar(const std::string& text) { return panels::yaml_string(text, "/"); }

std::string write_training_graph(const TrainingGraph& g, TrainingYamlLines* where) {
  CommentedLines out;
  TrainingYamlLines lines;
  out.comment_block(g.comment);
  out.add("training: " + yaml_scalar(g.name), "");
  if (!g.title.empty()) out.add("title: " + yaml_scalar(g.title), "");
  out.add("nodes:", "");
  for (const auto& n : g.nodes) {
    // max_attempts always written: the file says how often a node may repeat.
    const std::string task = n.task_path.empty() ? n.task_file : n.task_path;
    lines.nodes.push_back(out.add("  - {name: " + yaml_scalar(n.name) + ", task: " + yaml_scalar(task) +
                                      ", max_attempts: " + std::to_string(n.max_attempts) + "}",
                                  n.comment));
  }
  out.add("transitions:", "");
  for (const auto& t : g.transitions) {
    // The condition as written ("result LT 10" stays "result", not "score").
    const std::string cond = t.condition ? ", if: " + yaml_scalar(t.condition->text) : "";
    lines.transitions.push_back(
        out.add("  - {from: " + yaml_scalar(t.from) + cond + ", to: " + yaml_scalar(t.to) + "}", t.comment));
  }
  if (where) *where = lines;
  return out.text();
}

}  // namespace rise::sim::training
