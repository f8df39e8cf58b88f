#pragma once

// A training (the seed paper's section 2.5, Fig. 10): a graph of mission
// nodes between START and END whose transitions fire on conditions over the
// result of the task just finished ("if gameBombInsideHummer result LT 10
// then END"), with repeats and a maximum number of attempts per node.
// Loaded from YAML and validated; TrainingWalker follows it. Pure: no I/O
// beyond loading the files.

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "sim/training/task_description.hpp"
#include "sim/training/task_result.hpp"

namespace rise::sim::training {

inline constexpr const char* kStartNode = "START";
inline constexpr const char* kEndNode = "END";

enum class CompareOp { LT, LE, GT, GE, EQ, NE };
const char* to_string(CompareOp op);

/// "<field> <OP> <number>", e.g. "score LT 10"; fields as TaskResult::field
/// (`result` is another name for `score`, as in the seed's Fig. 11).
struct Condition {
  std::string field;
  CompareOp op = CompareOp::LT;
  double value = 0.0;
  std::string text;
  /// False when the result has no such field.
  bool holds(const TaskResult& result) const;
};
/// Throws std::invalid_argument naming what is wrong in `text`.
Condition parse_condition(const std::string& text);
/// What a condition may compare, as a builder offers it: the fields
/// (`events.<name>` besides these: the events of the task it leaves) and
/// the comparisons.
std::vector<std::string> condition_fields();
std::vector<std::string> condition_ops();

struct Transition {
  std::string from;  ///< START or a node
  std::string to;    ///< a node or END
  std::optional<Condition> condition;  ///< none: always
  int line = 0;
  std::string comment;  ///< the `# ...` ending its line in the file, kept by write_training_graph
};

struct TrainingNode {
  std::string name;
  std::string task_file;  ///< resolved against the training file's folder
  std::string task_path;  ///< as written in the file (task_file before resolving)
  int max_attempts = 3;   ///< runs of this node at most; a transition into an exhausted node is skipped
  int line = 0;
  std::optional<TaskDescription> task;  ///< loaded with the graph (load_tasks)
  std::string comment;  ///< the `# ...` ending its line in the file
};

struct TrainingGraph {
  std::string name;
  std::string title;
  std::string file;
  std::string comment;  ///< the comment lines before the first key, without their `# `
  std::vector<TrainingNode> nodes;
  std::vector<Transition> transitions;  ///< tried in file order
  const TrainingNode* node(const std::string& name) const;
};

/// Loads, then validates (validate_training_graph); with load_tasks every
/// node's task file is loaded too (its errors are the task file's). Throws
/// std::runtime_error "file:line: key: message"; validation errors, all of
/// them, one per line.
TrainingGraph load_training_graph(const std::string& path, bool load_tasks = true);
/// `validate` false: the graph as written, its graph errors not checked (a
/// builder shows them beside the entries); errors of the file's form still throw.
TrainingGraph parse_training_graph(const std::string& text, const std::string& file, bool load_tasks = true,
                                   bool validate = true);
/// The graph's errors, each "file:line: message": a transition from or to an
/// unknown node, no transition from START, a node unreachable from START, a
/// loop with no transition leaving it, a node with no path to END, a
/// condition on an event its node's task lacks. Empty = valid.
std::vector<std::string> validate_training_graph(const TrainingGraph& graph);

/// One finished task of a training, in order.
struct TrainingVisit {
  std::string node;
  int attempt = 1;
  TaskResult result;
  std::string transition;  ///< what followed, e.g. "score GE 20 → mission3"
};

/// Follows a validated graph: current() is the node to run next; record()
/// takes its result and the first transition from it, in file order, whose
/// condition holds and whose target has attempts left. Replaying the same
/// results gives the same walk (how a training resumes from its journal).
class TrainingWalker {
 public:
  explicit TrainingWalker(const TrainingGraph& graph);
  /// The node to run and its attempt number (1, 2, ...); nullopt once ended.
  std::optional<std::pair<std::string, int>> current() const;
  void record(const TaskResult& result);
  bool ended() const { return !current_; }
  const std::string& end_reason() const { return end_reason_; }
  const std::vector<TrainingVisit>& visits() const { return visits_; }
  int attempts(const std::string& node) const;
  int total_score() const;

 private:
  std::string step_from(const std::string& from, const TaskResult* result);

  const TrainingGraph* graph_;
  std::optional<std::string> current_;
  std::map<std::string, int> attempts_;
  std::vector<TrainingVisit> visits_;
  std::string end_reason_;
};

}  // namespace rise::sim::training
