#include "sim/training/training_graph.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "panels/yaml_reader.hpp"
#include "sim/training/yaml_comments.hpp"

namespace rise::sim::training {

using panels::YamlReader;

namespace {

struct OpName {
  CompareOp op;
  const char* name;
};
constexpr OpName kOps[] = {{CompareOp::LT, "LT"}, {CompareOp::LE, "LE"}, {CompareOp::GT, "GT"},
                           {CompareOp::GE, "GE"}, {CompareOp::EQ, "EQ"}, {CompareOp::NE, "NE"}};

bool known_field(const std::string& f) {
  return f == "score" || f == "time_s" || f == "success" || f == "damage" || f == "collisions" || f == "attempt" ||
         (f.rfind("events.", 0) == 0 && f.size() > 7);
}

std::string at(const TrainingGraph& g, int line) { return g.file + ":" + std::to_string(line) + ": "; }


// The graph as vertices (START, the nodes in file order, END) and the
// transitions between known vertices as edges, both ways.
struct Digraph {
  std::vector<std::string> names;
  std::vector<std::vector<int>> out, in;

  explicit Digraph(const TrainingGraph& g) {
    names.push_back(kStartNode);
    for (const auto& n : g.nodes) names.push_back(n.name);
    names.push_back(kEndNode);
    out.resize(names.size());
    in.resize(names.size());
  }
  static constexpr int kStart = 0;
  int end() const { return static_cast<int>(names.size()) - 1; }
  int index(const std::string& n) const {
    for (std::size_t i = 0; i < names.size(); ++i)
      if (names[i] == n) return static_cast<int>(i);
    return -1;
  }
};

// Where vertex v is declared: its node's line (START and END: line 1).
int line_of(const TrainingGraph& g, const Digraph& d, int v) {
  return v >= 1 && v < d.end() ? g.nodes[static_cast<std::size_t>(v - 1)].line : 1;
}

// A condition on events.<name> names an event of the task it leaves.
void check_condition_event(const TrainingGraph& g, const Transition& t, int from, std::vector<std::string>& errors) {
  const auto& task = g.nodes[static_cast<std::size_t>(from - 1)].task;
  const auto ev = t.condition->field.substr(7);
  bool has = false;
  if (task)
    for (const auto& e : task->events) has = has || e.name == ev;
  if (task && !has)
    errors.push_back(at(g, t.line) + "condition '" + t.condition->text + "': task " + task->name + " (" + task->file +
                     ") has no event '" + ev + "'");
}

// Each transition's ends and condition; the edges of the good ones go into d.
void add_transitions(const TrainingGraph& g, Digraph& d, std::vector<std::string>& errors) {
  const int start = Digraph::kStart, end = d.end();
  bool from_start = false;
  for (const auto& t : g.transitions) {
    const int a = d.index(t.from), b = d.index(t.to);
    if (a < 0 || a == end)
      errors.push_back(at(g, t.line) + "transition from '" + t.from + "': " +
                       (a == end ? "END has no transitions" : "unknown node"));
    if (b < 0 || b == start)
      errors.push_back(at(g, t.line) + "transition to '" + t.to + "': " +
                       (b == start ? "nothing goes back to START" : "unknown node"));
    if (a == start && t.condition)
      errors.push_back(at(g, t.line) + "transition from START: no condition allowed (there is no result yet)");
    if (a >= 0 && b >= 0 && a != end && b != start) {
      d.out[static_cast<std::size_t>(a)].push_back(b);
      d.in[static_cast<std::size_t>(b)].push_back(a);
      from_start = from_start || a == start;
    }
    if (t.condition && a > 0 && a < end && t.condition->field.rfind("events.", 0) == 0)
      check_condition_event(g, t, a, errors);
  }
  if (!from_start) errors.push_back(at(g, 1) + "no transition from START");
}

// The vertices reachable from `from` along adj.
std::vector<bool> reach(int from, const std::vector<std::vector<int>>& adj) {
  std::vector<bool> seen(adj.size(), false);
  std::vector<int> stack{from};
  seen[static_cast<std::size_t>(from)] = true;
  while (!stack.empty()) {
    const int v = stack.back();
    stack.pop_back();
    for (int w : adj[static_cast<std::size_t>(v)])
      if (!seen[static_cast<std::size_t>(w)]) {
        seen[static_cast<std::size_t>(w)] = true;
        stack.push_back(w);
      }
  }
  return seen;
}

// Strongly connected components (Tarjan): each vertex's component, numbered
// from 0 in the order they complete.
struct Components {
  std::vector<int> of;
  int count = 0;
};
Components strong_components(const std::vector<std::vector<int>>& out) {
  const std::size_t n = out.size();
  Components c;
  c.of.assign(n, -1);
  std::vector<int> low(n, 0), num(n, -1), stack;
  std::vector<bool> on(n, false);
  int counter = 0;
  std::function<void(int)> strong = [&](int v) {
    const auto vi = static_cast<std::size_t>(v);
    num[vi] = low[vi] = counter++;
    stack.push_back(v);
    on[vi] = true;
    for (int w : out[vi]) {
      const auto wi = static_cast<std::size_t>(w);
      if (num[wi] < 0) {
        strong(w);
        low[vi] = std::min(low[vi], low[wi]);
      } else if (on[wi]) {
        low[vi] = std::min(low[vi], num[wi]);
      }
    }
    if (low[vi] == num[vi]) {
      while (true) {
        const int w = stack.back();
        stack.pop_back();
        on[static_cast<std::size_t>(w)] = false;
        c.of[static_cast<std::size_t>(w)] = c.count;
        if (w == v) break;
      }
      ++c.count;
    }
  };
  for (int v = 0; v < static_cast<int>(n); ++v)
    if (num[static_cast<std::size_t>(v)] < 0) strong(v);
  return c;
}

// A reachable cycle none of whose members has a transition leaving it is
// a loop with no exit; returns the members of such loops.
std::set<int> check_closed_loops(const TrainingGraph& g, const Digraph& d, const std::vector<bool>& reachable,
                                 std::vector<std::string>& errors) {
  const Components comp = strong_components(d.out);
  std::set<int> closed_loop_members;
  for (int c = 0; c < comp.count; ++c) {
    std::vector<int> members;
    bool cycle = false, exit = false;
    for (int v = 0; v <= d.end(); ++v)
      if (comp.of[static_cast<std::size_t>(v)] == c) members.push_back(v);
    for (int v : members)
      for (int w : d.out[static_cast<std::size_t>(v)]) {
        if (comp.of[static_cast<std::size_t>(w)] == c) cycle = true;
        else exit = true;
      }
    if (!cycle || exit || !reachable[static_cast<std::size_t>(members.front())]) continue;
    std::string loop;
    for (int v : members) {
      loop += (loop.empty() ? "" : " → ") + d.names[static_cast<std::size_t>(v)];
      closed_loop_members.insert(v);
    }
    errors.push_back(at(g, line_of(g, d, members.front())) + "loop " + loop + " → " +
                     d.names[static_cast<std::size_t>(members.front())] +
                     " has no exit: no transition leaves it (its attempts run out with nowhere to go)");
  }
  return closed_loop_members;
}

}  // namespace

const char* to_string(CompareOp op) {
  for (const auto& o : kOps)
    if (o.op == op) return o.name;
  return "?";
}

std::vector<std::string> condition_fields() {
  return {"score", "result", "time_s", "success", "damage", "collisions", "attempt"};
}

std::vector<std::string> condition_ops() {
  std::vector<std::string> out;
  for (const auto& o : kOps) out.push_back(o.name);
  return out;
}

Condition parse_condition(const std::string& text) {
  std::istringstream in(text);
  std::string field, op, value, extra;
  in >> field >> op >> value >> extra;
  if (field.empty() || op.empty() || value.empty() || !extra.empty())
    throw std::invalid_argument("condition '" + text + "': expected '<field> <LT|LE|GT|GE|EQ|NE> <number>'");
  Condition c;
  c.text = text;
  c.field = field == "result" ? "score" : field;
  if (!known_field(c.field))
    throw std::invalid_argument("condition '" + text + "': unknown field '" + field +
                                "' (score or result, time_s, success, damage, collisions, attempt, events.<name>)");
  bool found = false;
  for (const auto& o : kOps)
    if (op == o.name) {
      c.op = o.op;
      found = true;
    }
  if (!found) throw std::invalid_argument("condition '" + text + "': unknown comparison '" + op + "' (LT, LE, GT, GE, EQ, NE)");
  char* end = nullptr;
  c.value = std::strtod(value.c_str(), &end);
  if (end != value.c_str() + value.size()) {
    if (value == "true" || value == "false") c.value = value == "true" ? 1.0 : 0.0;
    else throw std::invalid_argument("condition '" + text + "': '" + value + "' is not a number");
  }
  return c;
}

bool Condition::holds(const TaskResult& result) const {
  const auto v = result.field(field);
  if (!v) return false;
  switch (op) {
    case CompareOp::LT: return *v < value;
    case CompareOp::LE: return *v <= value;
    case CompareOp::GT: return *v > value;
    case CompareOp::GE: return *v >= value;
    case CompareOp::EQ: return *v == value;
    case CompareOp::NE: return *v != value;
  }
  return false;
}

const TrainingNode* TrainingGraph::node(const std::string& n) const {
  for (const auto& x : nodes)
    if (x.name == n) return &x;
  return nullptr;
}

TrainingGraph load_training_graph(const std::string& path, bool load_tasks) {
  return parse_training_graph(panels::read_text_file(path), path, load_tasks);
}

TrainingGraph parse_training_graph(const std::string& text, const std::string& file, bool load_tasks,
                                   bool validate) {
  const YamlReader r(file);
  const YAML::Node root = r.load_text(text);
  if (!root.IsMap()) r.fail(root, "", "expected a mapping with training:, nodes:, transitions:");
  r.only_keys(root, "", {"training", "title", "nodes", "transitions"});
  TrainingGraph g;
  g.file = file;
  g.comment = leading_comment(text);
  if (!root["training"]) r.fail(root, "training", "missing");
  g.name = r.as<std::string>(root["training"], "training");
  if (root["title"]) g.title = r.as<std::string>(root["title"], "title");
  const YAML::Node nodes = root["nodes"];
  if (!nodes || !nodes.IsSequence() || nodes.size() == 0) r.fail(nodes ? nodes : root, "nodes", "expected a non-empty list");
  std::set<std::string> names;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const YAML::Node n = nodes[i];
    const std::string where = "nodes[" + std::to_string(i) + "]";
    r.only_keys(n, where, {"name", "task", "max_attempts"});
    TrainingNode node;
    node.line = n.Mark().line + 1;
    for (const char* key : {"name", "task"})
      if (!n[key]) r.fail(n, where + "." + key, "missing");
    node.name = r.as<std::string>(n["name"], where + ".name");
    if (node.name.empty() || node.name == kStartNode || node.name == kEndNode)
      r.fail(n["name"], where + ".name", "must not be empty, START or END");
    if (!names.insert(node.name).second) r.fail(n["name"], where + ".name", "duplicate node '" + node.name + "'");
    const auto task = r.as<std::string>(n["task"], where + ".task");
    if (task.empty()) r.fail(n["task"], where + ".task", "must name a task file");
    node.task_path = task;
    node.comment = trailing_comment(text, node.line);
    node.task_file = std::filesystem::path(task).is_absolute()
                         ? task
                         : (std::filesystem::path(file).parent_path() / task).lexically_normal().string();
    if (n["max_attempts"]) {
      node.max_attempts = r.as<int>(n["max_attempts"], where + ".max_attempts");
      if (node.max_attempts < 1) r.fail(n["max_attempts"], where + ".max_attempts", "must be >= 1");
    }
    if (load_tasks) node.task = load_task_description(node.task_file);
    g.nodes.push_back(std::move(node));
  }
  const YAML::Node transitions = root["transitions"];
  if (!transitions || !transitions.IsSequence()) r.fail(transitions ? transitions : root, "transitions", "expected a list");
  for (std::size_t i = 0; i < transitions.size(); ++i) {
    const YAML::Node n = transitions[i];
    const std::string where = "transitions[" + std::to_string(i) + "]";
    r.only_keys(n, where, {"from", "to", "if"});
    Transition t;
    t.line = n.Mark().line + 1;
    t.comment = trailing_comment(text, t.line);
    for (const char* key : {"from", "to"})
      if (!n[key]) r.fail(n, where + "." + key, "missing");
    t.from = r.as<std::string>(n["from"], where + ".from");
    t.to = r.as<std::string>(n["to"], where + ".to");
    if (n["if"]) {
      try {
        t.condition = parse_condition(r.as<std::string>(n["if"], where + ".if"));
      } catch (const std::invalid_argument& e) {
        r.fail(n["if"], where + ".if", e.what());
      }
    }
    g.transitions.push_back(std::move(t));
  }
  const auto errors = validate ? validate_training_graph(g) : std::vector<std::string>{};
  if (!errors.empty()) {
    std::string all;
    for (const auto& e : errors) all += (all.empty() ? "" : "\n") + panels::printable(e);  // one line each
    throw std::runtime_error(all);
  }
  return g;
}

std::vector<std::string> validate_training_graph(const TrainingGraph& g) {
  std::vector<std::string> errors;
  Digraph d(g);
  add_transitions(g, d, errors);
  const auto reachable = reach(Digraph::kStart, d.out);
  const auto reaches_end = reach(d.end(), d.in);
  const std::set<int> closed_loop_members = check_closed_loops(g, d, reachable, errors);
  for (int v = 1; v < d.end(); ++v) {
    const auto vi = static_cast<std::size_t>(v);
    if (!reachable[vi])
      errors.push_back(at(g, line_of(g, d, v)) + "node '" + d.names[vi] + "' is unreachable from START");
    else if (!reaches_end[vi] && !closed_loop_members.count(v))
      errors.push_back(at(g, line_of(g, d, v)) + "node '" + d.names[vi] + "' has no path to END");
  }
  return errors;
}

TrainingWalker::TrainingWalker(const TrainingGraph& graph) : graph_(&graph) { step_from(kStartNode, nullptr); }

std::optional<std::pair<std::string, int>> TrainingWalker::current() const {
  if (!current_) return std::nullopt;
  return std::make_pair(*current_, attempts(*current_) + 1);
}

int TrainingWalker::attempts(const std::string& node) const {
  const auto it = attempts_.find(node);
  return it == attempts_.end() ? 0 : it->second;
}

int TrainingWalker::total_score() const {
  int sum = 0;
  for (const auto& v : visits_) sum += v.result.score;
  return sum;
}

std::string TrainingWalker::step_from(const std::string& from, const TaskResult* result) {
  bool exhausted = false;
  for (const auto& t : graph_->transitions) {
    if (t.from != from) continue;
    if (t.condition && (!result || !t.condition->holds(*result))) continue;
    if (t.to != kEndNode) {
      const auto* n = graph_->node(t.to);
      if (!n) continue;
      if (attempts(t.to) >= n->max_attempts) {
        exhausted = true;
        continue;
      }
      current_ = t.to;
    } else {
      current_.reset();
      end_reason_ = "END reached";
    }
    return (t.condition ? t.condition->text : std::string("always")) + " → " + t.to;
  }
  current_.reset();
  end_reason_ = exhausted ? "no transition from " + from + " left: the attempts of its targets are used up"
                          : "no transition from " + from + " applies";
  return "none (" + end_reason_ + ")";
}

void TrainingWalker::record(const TaskResult& result) {
  if (!current_) return;
  const std::string node = *current_;
  TrainingVisit v{node, ++attempts_[node], result, ""};
  v.result.node = node;
  v.result.attempt = v.attempt;
  v.transition = step_from(node, &v.result);
  visits_.push_back(std::move(v));
}

}  // namespace rise::sim::training
