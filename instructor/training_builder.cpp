#include "instructor/training_builder.hpp"

#include "instructor/builder_errors.hpp"

#include <filesystem>
#include <regex>
#include <sstream>
#include <stdexcept>

#include "instructor/design_files.hpp"
#include "panels/yaml_reader.hpp"
#include "sim/training/task_description.hpp"
#include "sim/training/training_writer.hpp"

namespace rise::instructor {
namespace fs = std::filesystem;
namespace tr = sim::training;

namespace {

constexpr Json::ArrayIndex kMaxNodes = 500, kMaxTransitions = 2000;
constexpr std::size_t kMaxText = 1000;

// body[key] as a string ("" when absent and optional); false with *error set otherwise.
bool read_string(const Json::Value& body, const char* key, const std::string& where, bool required, std::string* out,
                 std::string* error) {
  const Json::Value& v = body[key];
  const std::string k = where.empty() ? key : where + "." + key;
  if (v.isNull() && !required) return true;
  if (!v.isString()) return *error = k + ": expected a string", false;
  *out = v.asString();
  if (out->size() > kMaxText) return *error = k + ": longer than 1000 characters", false;
  if (out->find('\0') != std::string::npos) return *error = k + ": contains NUL", false;
  return true;
}

bool read_node(const Json::Value& n, const std::string& where, tr::TrainingNode* node, std::string* error) {
  if (!n.isObject()) return *error = where + ": expected an object", false;
  if (!read_string(n, "name", where, true, &node->name, error) ||
      !read_string(n, "task", where, true, &node->task_path, error) ||
      !read_string(n, "comment", where, false, &node->comment, error))
    return false;
  node->task_file = node->task_path;
  const Json::Value& m = n["max_attempts"];
  if (!m.isNull()) {
    if (!m.isInt()) return *error = where + ".max_attempts: expected a whole number", false;
    node->max_attempts = m.asInt();  // < 1: the loader names it with its line
  }
  return true;
}

bool read_transition(const Json::Value& t, const std::string& where, tr::Transition* out, std::string* error) {
  if (!t.isObject()) return *error = where + ": expected an object", false;
  std::string condition;
  if (!read_string(t, "from", where, true, &out->from, error) || !read_string(t, "to", where, true, &out->to, error) ||
      !read_string(t, "if", where, false, &condition, error) ||
      !read_string(t, "comment", where, false, &out->comment, error))
    return false;
  if (!condition.empty()) {
    tr::Condition c;  // as text: the loader parses it and names line and key
    c.text = condition;
    out->condition = c;
  }
  return true;
}

// A loader's error of the written training without a key: the node or
// transition its line holds.
BuilderError with_entry(BuilderError e, const std::string& path, const tr::TrainingYamlLines& lines) {
  if (e.key.empty() && e.line > 0 && e.file == fs::path(path).filename().string()) {
    for (std::size_t i = 0; i < lines.nodes.size(); ++i)
      if (lines.nodes[i] == e.line) e.key = "nodes[" + std::to_string(i) + "]";
    for (std::size_t i = 0; i < lines.transitions.size(); ++i)
      if (lines.transitions[i] == e.line) e.key = "transitions[" + std::to_string(i) + "]";
  }
  return e;
}

Json::Value task_json(const std::string& dir, const std::string& file) {
  Json::Value t;
  t["file"] = file;
  try {
    const tr::TaskDescription d = tr::load_task_description((fs::path(dir) / file).string());
    t["name"] = d.name;
    t["title"] = d.title;
    Json::Value events(Json::arrayValue);
    for (const auto& e : d.events) events.append(e.name);
    t["events"] = events;
  } catch (const std::exception& e) {
    t["error"] = e.what();
  }
  return t;
}

}  // namespace

Json::Value training_graph_json(const tr::TrainingGraph& g) {
  Json::Value v;
  v["training"] = g.name;
  v["title"] = g.title;
  v["comment"] = g.comment;
  Json::Value nodes(Json::arrayValue), transitions(Json::arrayValue);
  for (const auto& n : g.nodes) {
    Json::Value j;
    j["name"] = n.name;
    j["task"] = n.task_path.empty() ? n.task_file : n.task_path;
    j["max_attempts"] = n.max_attempts;
    j["comment"] = n.comment;
    nodes.append(j);
  }
  for (const auto& t : g.transitions) {
    Json::Value j;
    j["from"] = t.from;
    j["to"] = t.to;
    j["if"] = t.condition ? t.condition->text : "";
    j["comment"] = t.comment;
    transitions.append(j);
  }
  v["nodes"] = nodes;
  v["transitions"] = transitions;
  return v;
}

std::optional<tr::TrainingGraph> training_graph_from_json(const Json::Value& body, std::string* error) {
  if (!body.isObject()) return *error = "graph: expected an object", std::nullopt;
  tr::TrainingGraph g;
  if (!read_string(body, "training", "", true, &g.name, error) || !read_string(body, "title", "", false, &g.title, error))
    return std::nullopt;
  const Json::Value& comment = body["comment"];
  if (!comment.isNull()) {
    if (!comment.isString() || comment.asString().size() > 20 * kMaxText) return *error = "comment: expected a string", std::nullopt;
    g.comment = comment.asString();
    if (g.comment.find('\0') != std::string::npos) return *error = "comment: contains NUL", std::nullopt;
  }
  const Json::Value &nodes = body["nodes"], &transitions = body["transitions"];
  if (!nodes.isArray() || nodes.size() > kMaxNodes) return *error = "nodes: expected a list (at most 500)", std::nullopt;
  if (!transitions.isArray() || transitions.size() > kMaxTransitions)
    return *error = "transitions: expected a list (at most 2000)", std::nullopt;
  for (Json::ArrayIndex i = 0; i < nodes.size(); ++i) {
    tr::TrainingNode n;
    if (!read_node(nodes[i], "nodes[" + std::to_string(i) + "]", &n, error)) return std::nullopt;
    g.nodes.push_back(std::move(n));
  }
  for (Json::ArrayIndex i = 0; i < transitions.size(); ++i) {
    tr::Transition t;
    if (!read_transition(transitions[i], "transitions[" + std::to_string(i) + "]", &t, error)) return std::nullopt;
    g.transitions.push_back(std::move(t));
  }
  return g;
}

TrainingCheck check_training(const tr::TrainingGraph& graph, const std::string& path) {
  TrainingCheck out;
  tr::TrainingYamlLines lines;
  out.yaml = tr::write_training_graph(graph, &lines);
  const std::string file = fs::path(path).filename().string();
  // Tasks from this folder only: the page offers them, and no request reads
  // a file elsewhere through the task loader.
  for (std::size_t i = 0; i < graph.nodes.size(); ++i) {
    const std::string& task = graph.nodes[i].task_path;
    if (!valid_design_name(task, ".yaml"))
      out.errors.push_back({file, lines.nodes[i], "nodes[" + std::to_string(i) + "].task",
                            "'" + task + "': expected a task file of this folder (name.yaml, no folder)"});
  }
  if (!out.errors.empty()) return out;
  try {
    tr::parse_training_graph(out.yaml, path, true);
  } catch (const std::exception& e) {
    for (auto& err : loader_errors(e.what(), path)) out.errors.push_back(with_entry(std::move(err), path, lines));
  }
  return out;
}

Json::Value check_json(const TrainingCheck& check) { return check_json(check.yaml, check.errors); }

Json::Value training_files_json(const std::string& dir, const std::vector<std::string>& yaml_files) {
  static const std::regex training_key("(^|\n)training:");  // as rise-trainer check tells them apart
  Json::Value v, trainings(Json::arrayValue), tasks(Json::arrayValue), fields(Json::arrayValue), ops(Json::arrayValue);
  v["dir"] = dir;
  for (const auto& file : yaml_files) {
    const std::string path = (fs::path(dir) / file).string();
    std::string text;
    try {
      text = panels::read_text_file(path);
    } catch (const std::exception&) {
      continue;
    }
    if (!std::regex_search(text, training_key)) {
      tasks.append(task_json(dir, file));
      continue;
    }
    Json::Value t;
    t["file"] = file;
    try {
      const auto g = tr::parse_training_graph(text, path, false);
      t["name"] = g.name;
      t["title"] = g.title;
    } catch (const std::exception& e) {
      t["error"] = e.what();
    }
    trainings.append(t);
  }
  for (const auto& f : tr::condition_fields()) fields.append(f);
  for (const auto& o : tr::condition_ops()) ops.append(o);
  v["trainings"] = trainings;
  v["tasks"] = tasks;
  v["fields"] = fields;
  v["ops"] = ops;
  return v;
}

}  // namespace rise::instructor
