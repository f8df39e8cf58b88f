#include "sim/training/task_description.hpp"

#include <cmath>
#include <filesystem>
#include <set>

#include "panels/yaml_reader.hpp"

namespace rise::sim::training {

using panels::YamlReader;

namespace {

struct KindName {
  TaskEventKind kind;
  const char* name;
};
constexpr KindName kKinds[] = {
    {TaskEventKind::ReachRegion, "reach_region"},       {TaskEventKind::TimeExceeded, "time_exceeded"},
    {TaskEventKind::ObjectInRegion, "object_in_region"}, {TaskEventKind::TouchObject, "touch_object"},
    {TaskEventKind::RobotDamaged, "robot_damaged"},     {TaskEventKind::RobotDisabled, "robot_disabled"},
    {TaskEventKind::NeutralizeObject, "neutralize_object"}, {TaskEventKind::Collision, "collision"},
};

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
           "unknown kind '" + kind_text +
               "' (reach_region, time_exceeded, object_in_region, touch_object, robot_damaged, robot_disabled, "
               "neutralize_object, collision)");
  e.kind = *kind;
  if (n["points"]) e.points = r.as<int>(n["points"], where + ".points");
  e.max_count = (e.kind == TaskEventKind::Collision || e.kind == TaskEventKind::RobotDamaged) ? 0 : 1;
  if (n["max_count"]) {
    e.max_count = r.as<int>(n["max_count"], where + ".max_count");
    if (e.max_count < 0) r.fail(n["max_count"], where + ".max_count", "must be >= 0 (0: no limit)");
  }
  const auto need = [&](const char* key, std::string& out) {
    if (!n[key]) r.fail(n, where + "." + key, std::string("missing (kind ") + to_string(e.kind) + " needs it)");
    out = r.as<std::string>(n[key], where + "." + key);
  };
  const auto refuse = [&](const char* key) {
    if (n[key]) r.fail(n[key], where + "." + key, std::string("not for kind ") + to_string(e.kind));
  };
  switch (e.kind) {
    case TaskEventKind::ReachRegion:
      need("region", e.region);
      break;
    case TaskEventKind::ObjectInRegion:
      need("region", e.region);
      need("object", e.object);
      break;
    case TaskEventKind::TouchObject:
    case TaskEventKind::NeutralizeObject:
      need("object", e.object);
      break;
    default:
      break;
  }
  if (e.kind != TaskEventKind::ReachRegion && e.kind != TaskEventKind::ObjectInRegion) refuse("region");
  if (e.kind != TaskEventKind::ObjectInRegion && e.kind != TaskEventKind::TouchObject &&
      e.kind != TaskEventKind::NeutralizeObject)
    refuse("object");
  if (e.kind == TaskEventKind::TimeExceeded) {
    if (!n["after_s"]) r.fail(n, where + ".after_s", "missing (kind time_exceeded needs it)");
    e.after_s = r.positive(n, "after_s", where, 0.0);
  } else {
    refuse("after_s");
  }
  if (e.kind == TaskEventKind::ObjectInRegion || e.kind == TaskEventKind::NeutralizeObject)
    e.hold_s = r.positive(n, "hold_s", where, 0.0, true);
  else
    refuse("hold_s");
  if (e.kind == TaskEventKind::NeutralizeObject)
    e.within_m = r.positive(n, "within_m", where, 0.0, true);
  else
    refuse("within_m");
  if (e.kind == TaskEventKind::Collision) {
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
  } else {
    refuse("per");
    refuse("except");
  }
  return e;
}

}  // namespace

const char* to_string(TaskEventKind kind) {
  for (const auto& k : kKinds)
    if (k.kind == kind) return k.name;
  return "unknown";
}

std::optional<TaskEventKind> task_event_kind(const std::string& name) {
  for (const auto& k : kKinds)
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
  t.robot_file = resolve(file, r.as<std::string>(root["robot"], "robot"));
  t.world_file = resolve(file, r.as<std::string>(root["world"], "world"));
  if (root["panel"]) t.panel_file = resolve(file, r.as<std::string>(root["panel"], "panel"));
  if (root["console_script"])
    t.console_script = resolve(file, r.as<std::string>(root["console_script"], "console_script"));
  if (root["scenario"]) t.scenario_file = resolve(file, r.as<std::string>(root["scenario"], "scenario"));
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
    for (std::size_t i = 0; i < regions.size(); ++i) t.regions.push_back(read_region(r, regions[i], item("regions", i)));
  }
  const YAML::Node events = root["events"];
  if (!events || !events.IsSequence() || events.size() == 0)
    r.fail(events ? events : root, "events", "expected a non-empty list");
  std::set<std::string> seen;
  for (std::size_t i = 0; i < events.size(); ++i) {
    const auto where = item("events", i);
    t.events.push_back(read_event(r, events[i], where));
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
