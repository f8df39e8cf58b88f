#include "sim/training/task_writer.hpp"

#include <cmath>
#include <cstdio>

#include "sim/training/training_writer.hpp"  // yaml_scalar
#include "sim/training/yaml_comments.hpp"

namespace rise::sim::training {

namespace {

template <class T>
std::string flow_list(const T& values, std::string (*format)(typename T::value_type)) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i) out += (i ? ", " : "") + format(values[i]);
  return out + "]";
}

std::string number(double v) { return yaml_number(v); }
std::string scalar(std::string s) { return yaml_scalar(s); }

std::string region_entry(const Region& g) {
  return "  - {name: " + yaml_scalar(g.name) + ", min: " + flow_list(g.min_m, number) +
         ", max: " + flow_list(g.max_m, number) + "}";
}

// The keys of one event past name and kind, in the order of its kind's table.
std::string event_params(const TaskEventSpec& e) {
  const TaskEventKindInfo& info = task_event_kind_info(e.kind);
  std::string out;
  for (const auto& p : info.params) {
    const std::string key = p.key;
    if (key == "region") out += ", region: " + yaml_scalar(e.region);
    if (key == "object") out += ", object: " + yaml_scalar(e.object);
    if (key == "after_s") out += ", after_s: " + yaml_number(e.after_s);
    if (key == "hold_s" && e.hold_s != 0) out += ", hold_s: " + yaml_number(e.hold_s);
    if (key == "within_m" && e.within_m != 0) out += ", within_m: " + yaml_number(e.within_m);
    if (key == "per" && e.per_second) out += ", per: second";
    if (key == "except" && !e.except.empty()) out += ", except: " + flow_list(e.except, scalar);
  }
  return out;
}

std::string event_entry(const TaskEventSpec& e) {
  std::string out = "  - {name: " + yaml_scalar(e.name) + ", kind: " + to_string(e.kind) + event_params(e);
  out += ", points: " + std::to_string(e.points);
  if (e.max_count != task_event_kind_info(e.kind).default_max_count) out += ", max_count: " + std::to_string(e.max_count);
  return out + "}";
}

std::string comment_of(const TaskDescription& t, const std::string& key) {
  const auto it = t.key_comments.find(key);
  return it == t.key_comments.end() ? "" : it->second;
}

}  // namespace

std::string yaml_number(double value) {
  if (value == 0) return "0";  // never "-0"
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.10g", value);
  return buf;
}

std::string write_task_description(const TaskDescription& t, TaskYamlLines* where) {
  CommentedLines out;
  TaskYamlLines lines;
  const auto key = [&](const std::string& k, const std::string& value) {
    lines.keys[k] = out.add(k + ":" + (value.empty() ? "" : " " + value), comment_of(t, k));
  };
  out.comment_block(t.comment);
  key("task", yaml_scalar(t.name));
  if (!t.title.empty()) key("title", yaml_scalar(t.title));
  key("robot", yaml_scalar(t.robot_path));
  key("world", yaml_scalar(t.world_path));
  if (!t.panel_path.empty()) key("panel", yaml_scalar(t.panel_path));
  if (!t.console_script_path.empty()) key("console_script", yaml_scalar(t.console_script_path));
  if (!t.scenario_path.empty()) key("scenario", yaml_scalar(t.scenario_path));
  if (t.start)
    key("start", "{xy_m: " + flow_list(t.start->xy_m, number) +
                     ", yaw_deg: " + yaml_number(t.start->yaw_rad * 180.0 / M_PI) + "}");
  key("time_limit_s", yaml_number(t.time_limit_s));
  if (!t.regions.empty()) {
    key("regions", "");
    for (std::size_t i = 0; i < t.regions.size(); ++i)
      lines.regions.push_back(
          out.add(region_entry(t.regions[i]), i < t.region_comments.size() ? t.region_comments[i] : ""));
  }
  key("events", "");
  for (const auto& e : t.events) lines.events.push_back(out.add(event_entry(e), e.comment));
  if (!t.end_on.empty()) key("end_on", flow_list(t.end_on, scalar));
  if (!t.success.empty()) key("success", flow_list(t.success, scalar));
  if (where) *where = lines;
  return out.text();
}

}  // namespace rise::sim::training
