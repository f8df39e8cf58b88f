#include "sim/training/task_description.hpp"

#include <cmath>
#include <filesystem>
#include <set>

#include "panels/yaml_reader.hpp"
#include "sim/training/yaml_comments.hpp"

namespace rise::sim::training {

using panels::YamlReader;

namespace {

// Every key an event kind may take beyond name/kind/points/max_count; a kind
// refuses the ones its entry of task_event_kinds() does not list.
constexpr const char* kParamKeys[] = {"region", "object", "after_s", "hold_s", "within_m", "per", "except"};

bool takes(const TaskEventKindInfo& info, const std::string& key) {
  for (const auto& p : info.params)
    if (key == p.key) return true;
  return false;
}

std::string kind_names() {
  std::string out;
  for (const auto& k : task_event_kinds()) out += (out.empty() ? "" : ", ") + std::string(k.name);
  return out;
}

std::string resolve(const std::string& task_file, const std::string& relative) {
  if (relative.empty() || std::filesystem::path(relative).is_absolute()) return relative;
  return (std::filesystem::path(task_file).parent_path() / relative).lexically_normal().string();
}

std::string item(const char* key, std::size_t i) { return std::string(key) + "[" + std::to_string(i) + "]"; }

std::vector<std::string> names(const YamlReader& r, const YAML::Node& root, const char* key) {
  std::vector<std::string> out;
  const YAML::Node n = root[key];
  if (!n) return out;
  if (!n.IsSequence()) r.fail(n, key, "expected a list of event names");
  for (std::size_t i = 0; i < n.size(); ++i) out.push_back(r.as<std::string>(n[i], item(key, i)));
  return out;
}

Region read_region(const YamlReader& r, const YAML::Node& n, const std::string& where) {
  r.only_keys(n, where, {"name", "min", "max"});
  Region g;
  if (!n["name"]) r.fail(n, where + ".name", "missing");
  g.name = r.as<std::string>(n["name"], where + ".name");
  g.min_m = r.vector<3>(n, "min", where);
  g.max_m = r.vector<3>(n, "max", where);
  for (std::size_t k = 0; k < 3; ++k)
    if (!(g.min_m[k] < g.max_m[k])) r.fail(n["max"], where + ".max", "must be > min on every axis");
  return g;
}

TaskEventSpec read_event(const YamlReader& r, const YAML::Node& n, const std::string& where) {
  r.only_keys(n, where,
              {"name", "kind", "points", "max_count", "region", "object", "after_s", "hold_s", "within_m", "per",
               "except"});
  TaskEventSpec e;
  e.line = n.Mark().line + 1;
  if (!n["name"]) r.fail(n, where + ".name", "missing");
  e.name = r.as<std::string>(n["name"], where + ".name");
  if (e.name.empty()) r.fail(n["name"], where + ".name", "must not be empty");
  if (!n["kind"]) r.fail(n, where + ".kind", "missing");
  const auto kind_text = r.as<std::string>(n["kind"], where + ".kind");
  const auto kind = task_event_kind(kind_text);
  if (!kind)
    r.fail(n["kind"], where + ".kind",
           "unknown kind '" + kind_text + "' (" + kind_names() + ")");
  e.kind = *kind;
  if (n["points"]) e.points = r.as<int>(n["points"], where + ".points");
  e.max_count = task_event_kind_info(e.kind).default_max_count;
  if (n["max_count"]) {
    e.max_count = r.as<int>(n["max_count"], where + ".max_count");
    if (e.max_count < 0) r.fail(n["max_count"], where + ".max_count", "must be >= 0 (0: no limit)");
  }
  const TaskEventKindInfo& info = task_event_kind_info(e.kind);
  for (const char* key : kParamKeys)
    if (n[key] && !takes(info, key)) r.fail(n[key], where + "." + key, std::string("not for kind ") + info.name);
  for (const auto& p : info.params)
    if (p.required && !n[p.key]) r.fail(n, where + "." + p.key, std::string("missing (kind ") + info.name + " needs it)");
  if (n["region"]) e.region = r.as<std::string>(n["region"], where + ".region");
  if (n["object"]) e.object = r.as<std::string>(n["object"], where + ".object");
  if (n["after_s"]) e.after_s = r.positive(n, "after_s", where, 0.0);
  if (takes(info, "hold_s")) e.hold_s = r.positive(n, "hold_s", where, 0.0, true);
  if (takes(info, "within_m")) e.within_m = r.positive(n, "within_m", where, 0.0, true);
  if (n["per"]) {
    const auto per = r.as<std::string>(n["per"], where + ".per");
    if (per != "collision" && per != "second")
      r.fail(n["per"], where + ".per", "'" + per + "': expected collision or second");
    e.per_second = per == "second";
  }
  if (n["except"]) {
    if (!n["except"].IsSequence()) r.fail(n["except"], where + ".except", "expected a list of entity names");
    for (std::size_t i = 0; i < n["except"].size(); ++i)
      e.except.push_back(r.as<std::string>(n["except"][i], where + "." + item("except", i)));
  }
  return e;
}

// The files the task names, as written and resolved against its folder.
void read_paths(const YamlReader& r, const YAML::Node& root, TaskDescription* t) {
  const auto path = [&](const char* key, std::string* as_written, std::string* resolved) {
    if (!root[key]) return;
    *as_written = r.as<std::string>(root[key], key);
    *resolved = resolve(t->file, *as_written);
  };
  path("robot", &t->robot_path, &t->robot_file);
  path("world", &t->world_path, &t->world_file);
  path("panel", &t->panel_path, &t->panel_file);
  path("console_script", &t->console_script_path, &t->console_script);
  path("scenario", &t->scenario_path, &t->scenario_file);
}

// The file's opening comment and the comments ending its top-level keys' lines.
void read_comments(const std::string& text, const YAML::Node& root, TaskDescription* t) {
  t->comment = leading_comment(text);
  for (const auto& kv : root) {
    const int line = kv.first.Mark().line + 1;
    // A block list's comment on its key's line, a flow value's on the line it ends.
    const std::string c = trailing_comment(text, line);
    if (!c.empty()) t->key_comments[kv.first.as<std::string>()] = c;
  }
}

}  // namespace

const std::vector<TaskEventKindInfo>& task_event_kinds() {
  using K = TaskEventKind;
  static const TaskEventParam region{"region", "region", true, "the region (task or world) the robot's base enters"};
  static const TaskEventParam object{"object", "object", true, "the world's object"};
  static const std::vector<TaskEventKindInfo> kinds{
      {K::ReachRegion, "reach_region", "the robot's base enters a region", 1, {region}},
      {K::TimeExceeded, "time_exceeded", "task time reaches after_s", 1,
       {{"after_s", "seconds", true, "task time at which it fires"}}},
      {K::ObjectInRegion, "object_in_region", "an object's centre inside a region for hold_s", 1,
       {{"region", "region", true, "the region it must be in"},
        {"object", "object", true, "the object that must be inside"},
        {"hold_s", "seconds", false, "continuously for this long (0: at once)"}}},
      {K::TouchObject, "touch_object", "a robot part starts touching the object", 1, {object}},
      {K::RobotDamaged, "robot_damaged", "a robot joint breaks", 0, {}},
      {K::RobotDisabled, "robot_disabled", "the robot tips over or its damage reaches 1", 1, {}},
      {K::NeutralizeObject, "neutralize_object", "the gripper on the object (or within within_m of it) for hold_s", 1,
       {object, {"hold_s", "seconds", false, "continuously for this long"},
        {"within_m", "metres", false, "0: gripper contact; > 0: the finger's centre this close to the object's"}}},
      {K::Collision, "collision", "a penalty per collision, or per second of contact", 0,
       {{"per", "per", false, "collision (each one) or second (of contact)"},
        {"except", "names", false, "entities whose contact does not count"}}},
  };
  return kinds;
}

const TaskEventKindInfo& task_event_kind_info(TaskEventKind kind) {
  for (const auto& k : task_event_kinds())
    if (k.kind == kind) return k;
  return task_event_kinds().front();
}

const char* to_string(TaskEventKind kind) {
  for (const auto& k : task_event_kinds())
    if (k.kind == kind) return k.name;
  return "unknown";
}

std::optional<TaskEventKind> task_event_kind(const std::string& name) {
  for (const auto& k : task_event_kinds())
    if (name == k.name) return k.kind;
  return std::nullopt;
}

TaskDescription load_task_description(const std::string& path) {
  return parse_task_description(panels::read_text_file(path), path);
}

TaskDescription parse_task_description(const std::string& text, const std::string& file) {
  const YamlReader r(file);
  const YAML::Node root = r.load_text(text);
  if (!root.IsMap()) r.fail(root, "", "expected a mapping with task:, robot:, world:, events:");
  r.only_keys(root, "",
              {"task", "title", "robot", "world", "panel", "console_script", "start", "time_limit_s", "events",
               "regions", "end_on", "success", "scenario"});
  TaskDescription t;
  t.file = file;
  for (const char* key : {"task", "robot", "world"})
    if (!root[key]) r.fail(root, key, "missing");
  t.name = r.as<std::string>(root["task"], "task");
  if (root["title"]) t.title = r.as<std::string>(root["title"], "title");
  read_paths(r, root, &t);
  read_comments(text, root, &t);
  if (const YAML::Node s = root["start"]) {
    r.only_keys(s, "start", {"xy_m", "yaw_deg"});
    RobotStart start;
    start.xy_m = r.vector<2>(s, "xy_m", "start");
    if (s["yaw_deg"]) start.yaw_rad = r.as<double>(s["yaw_deg"], "start.yaw_deg") * M_PI / 180.0;
    t.start = start;
  }
  if (const YAML::Node n = root["time_limit_s"]) {
    t.time_limit_s = r.as<double>(n, "time_limit_s");
    if (!(t.time_limit_s > 0)) r.fail(n, "time_limit_s", "must be > 0");
  }
  if (const YAML::Node regions = root["regions"]) {
    if (!regions.IsSequence()) r.fail(regions, "regions", "expected a list");
    for (std::size_t i = 0; i < regions.size(); ++i) {
      t.regions.push_back(read_region(r, regions[i], item("regions", i)));
      t.region_lines.push_back(regions[i].Mark().line + 1);
      t.region_comments.push_back(trailing_comment(text, t.region_lines.back()));
    }
  }
  const YAML::Node events = root["events"];
  if (!events || !events.IsSequence() || events.size() == 0)
    r.fail(events ? events : root, "events", "expected a non-empty list");
  std::set<std::string> seen;
  for (std::size_t i = 0; i < events.size(); ++i) {
    const auto where = item("events", i);
    t.events.push_back(read_event(r, events[i], where));
    t.events.back().comment = trailing_comment(text, t.events.back().line);
    if (!seen.insert(t.events.back().name).second)
      r.fail(events[i]["name"], where + ".name", "duplicate event name '" + t.events.back().name + "'");
  }
  t.end_on = names(r, root, "end_on");
  t.success = names(r, root, "success");
  for (const char* key : {"end_on", "success"}) {
    const auto& list = std::string(key) == "end_on" ? t.end_on : t.success;
    for (std::size_t i = 0; i < list.size(); ++i)
      if (!seen.count(list[i])) r.fail(root[key][i], item(key, i), "unknown event '" + list[i] + "'");
  }
  return t;
}

void check_against_world(const TaskDescription& task, const WorldDescription& world) {
  std::set<std::string> regions, objects;
  for (const auto& g : world.regions) regions.insert(g.name);
  for (const auto& g : task.regions) regions.insert(g.name);
  for (const auto& o : world.objects) objects.insert(o.name);
  for (std::size_t i = 0; i < task.events.size(); ++i) {
    const auto& e = task.events[i];
    const std::string at = task.file + ":" + std::to_string(e.line) + ": " + item("events", i);
    if (!e.region.empty() && !regions.count(e.region))
      throw std::runtime_error(at + ".region: no region '" + e.region + "' in the task or in world " + world.file);
    if (!e.object.empty() && !objects.count(e.object))
      throw std::runtime_error(at + ".object: no object '" + e.object + "' in world " + world.file);
  }
}

}  // namespace rise::sim::training
