#include "instructor/task_builder.hpp"

#include "instructor/builder_errors.hpp"

#include <cmath>
#include <filesystem>
#include <regex>

#include "panels/yaml_reader.hpp"
#include "sim/training/task_writer.hpp"
#include "sim/world_description.hpp"

namespace rise::instructor {
namespace fs = std::filesystem;
namespace tr = sim::training;

namespace {

constexpr Json::ArrayIndex kMaxEntries = 500;
constexpr std::size_t kMaxText = 1000;

// body[key] as a string ("" when absent and optional); false with *error set otherwise.
bool read_string(const Json::Value& body, const char* key, const std::string& where, bool required, std::string* out,
                 std::string* error, std::size_t max = kMaxText) {
  const Json::Value& v = body[key];
  const std::string k = where.empty() ? key : where + "." + key;
  if (v.isNull() && !required) return true;
  if (!v.isString()) return *error = k + ": expected a string", false;
  *out = v.asString();
  if (out->size() > max) return *error = k + ": too long", false;
  if (out->find('\0') != std::string::npos) return *error = k + ": contains NUL", false;
  return true;
}

bool read_number(const Json::Value& body, const char* key, const std::string& where, double* out, std::string* error) {
  const Json::Value& v = body[key];
  if (v.isNull()) return true;
  if (!v.isNumeric() || !std::isfinite(v.asDouble())) return *error = where + "." + key + ": expected a number", false;
  *out = v.asDouble();
  return true;
}

bool read_int(const Json::Value& body, const char* key, const std::string& where, int* out, std::string* error) {
  const Json::Value& v = body[key];
  if (v.isNull()) return true;
  if (!v.isInt()) return *error = where + "." + key + ": expected a whole number", false;
  *out = v.asInt();
  return true;
}

bool read_names(const Json::Value& body, const char* key, const std::string& where, std::vector<std::string>* out,
                std::string* error) {
  const Json::Value& v = body[key];
  const std::string k = where.empty() ? key : where + "." + key;
  if (v.isNull()) return true;
  if (!v.isArray() || v.size() > kMaxEntries) return *error = k + ": expected a list of names", false;
  for (Json::ArrayIndex i = 0; i < v.size(); ++i) {
    if (!v[i].isString() || v[i].asString().size() > kMaxText) return *error = k + ": expected a list of names", false;
    out->push_back(v[i].asString());
  }
  return true;
}

bool read_xyz(const Json::Value& body, const char* key, const std::string& where, std::array<double, 3>* out,
              std::string* error) {
  const Json::Value& v = body[key];
  if (!v.isArray() || v.size() != 3) return *error = where + "." + key + ": expected [x, y, z]", false;
  for (Json::ArrayIndex i = 0; i < 3; ++i) {
    if (!v[i].isNumeric() || !std::isfinite(v[i].asDouble())) return *error = where + "." + key + ": expected [x, y, z]", false;
    (*out)[i] = v[i].asDouble();
  }
  return true;
}

bool read_region(const Json::Value& r, const std::string& where, tr::TaskDescription* t, std::string* error) {
  if (!r.isObject()) return *error = where + ": expected an object", false;
  sim::Region g;
  std::string comment;
  if (!read_string(r, "name", where, true, &g.name, error) || !read_xyz(r, "min", where, &g.min_m, error) ||
      !read_xyz(r, "max", where, &g.max_m, error) || !read_string(r, "comment", where, false, &comment, error))
    return false;
  t->regions.push_back(g);
  t->region_comments.push_back(comment);
  return true;
}

bool read_event(const Json::Value& e, const std::string& where, tr::TaskEventSpec* out, std::string* error) {
  if (!e.isObject()) return *error = where + ": expected an object", false;
  std::string kind, per;
  if (!read_string(e, "name", where, true, &out->name, error) || !read_string(e, "kind", where, true, &kind, error) ||
      !read_string(e, "region", where, false, &out->region, error) ||
      !read_string(e, "object", where, false, &out->object, error) ||
      !read_string(e, "per", where, false, &per, error) || !read_string(e, "comment", where, false, &out->comment, error) ||
      !read_names(e, "except", where, &out->except, error))
    return false;
  const auto k = tr::task_event_kind(kind);
  if (!k) return *error = where + ".kind: unknown kind '" + kind + "'", false;
  out->kind = *k;
  out->max_count = tr::task_event_kind_info(*k).default_max_count;
  out->per_second = per == "second";
  return read_int(e, "points", where, &out->points, error) && read_int(e, "max_count", where, &out->max_count, error) &&
         read_number(e, "after_s", where, &out->after_s, error) && read_number(e, "hold_s", where, &out->hold_s, error) &&
         read_number(e, "within_m", where, &out->within_m, error);
}

bool read_start(const Json::Value& s, tr::TaskDescription* t, std::string* error) {
  if (s.isNull()) return true;
  if (!s.isObject()) return *error = "start: expected {x, y, yaw_deg} or null", false;
  double x = 0, y = 0, yaw = 0;
  if (!read_number(s, "x", "start", &x, error) || !read_number(s, "y", "start", &y, error) ||
      !read_number(s, "yaw_deg", "start", &yaw, error))
    return false;
  sim::RobotStart start;
  start.xy_m = {x, y};
  start.yaw_rad = yaw * M_PI / 180.0;
  t->start = start;
  return true;
}

bool read_header(const Json::Value& b, tr::TaskDescription* t, std::string* error) {
  return read_string(b, "task", "", true, &t->name, error) && read_string(b, "title", "", false, &t->title, error) &&
         read_string(b, "comment", "", false, &t->comment, error, 20 * kMaxText) &&
         read_string(b, "robot", "", true, &t->robot_path, error) &&
         read_string(b, "world", "", true, &t->world_path, error) &&
         read_string(b, "panel", "", false, &t->panel_path, error) &&
         read_string(b, "console_script", "", false, &t->console_script_path, error) &&
         read_string(b, "scenario", "", false, &t->scenario_path, error) && read_start(b["start"], t, error) &&
         read_number(b, "time_limit_s", "", &t->time_limit_s, error) &&
         read_names(b, "end_on", "", &t->end_on, error) && read_names(b, "success", "", &t->success, error);
}

bool read_key_comments(const Json::Value& v, tr::TaskDescription* t, std::string* error) {
  if (v.isNull()) return true;
  if (!v.isObject()) return *error = "key_comments: expected an object", false;
  for (const auto& key : v.getMemberNames()) {
    if (!v[key].isString() || v[key].asString().size() > kMaxText) return *error = "key_comments." + key + ": expected a string", false;
    t->key_comments[key] = v[key].asString();
  }
  return true;
}

Json::Value names_json(const std::vector<std::string>& names) {
  Json::Value a(Json::arrayValue);
  for (const auto& n : names) a.append(n);
  return a;
}

Json::Value xyz_json(const std::array<double, 3>& v) {
  Json::Value a(Json::arrayValue);
  for (double x : v) a.append(x);
  return a;
}

Json::Value event_json(const tr::TaskEventSpec& e) {
  Json::Value j;
  j["name"] = e.name;
  j["kind"] = tr::to_string(e.kind);
  j["points"] = e.points;
  j["max_count"] = e.max_count;
  j["region"] = e.region;
  j["object"] = e.object;
  j["after_s"] = e.after_s;
  j["hold_s"] = e.hold_s;
  j["within_m"] = e.within_m;
  j["per"] = e.per_second ? "second" : "collision";
  j["except"] = names_json(e.except);
  j["comment"] = e.comment;
  return j;
}

// The entry of the written text that line `line` holds ("events[2]", "start"), or "".
std::string entry_at(const tr::TaskYamlLines& lines, int line) {
  for (std::size_t i = 0; i < lines.events.size(); ++i)
    if (lines.events[i] == line) return "events[" + std::to_string(i) + "]";
  for (std::size_t i = 0; i < lines.regions.size(); ++i)
    if (lines.regions[i] == line) return "regions[" + std::to_string(i) + "]";
  for (const auto& [key, l] : lines.keys)
    if (l == line) return key;
  return "";
}

// A loader's error of the written task without a key: the entry its line holds.
BuilderError with_entry(BuilderError e, const std::string& path, const tr::TaskYamlLines& lines) {
  if (e.key.empty() && e.line > 0 && e.file == fs::path(path).filename().string()) e.key = entry_at(lines, e.line);
  return e;
}

}  // namespace

Json::Value task_json(const tr::TaskDescription& t) {
  Json::Value v;
  v["task"] = t.name;
  v["title"] = t.title;
  v["comment"] = t.comment;
  v["robot"] = t.robot_path;
  v["world"] = t.world_path;
  v["panel"] = t.panel_path;
  v["console_script"] = t.console_script_path;
  v["scenario"] = t.scenario_path;
  v["start"] = Json::nullValue;
  if (t.start) {
    v["start"]["x"] = t.start->xy_m[0];
    v["start"]["y"] = t.start->xy_m[1];
    v["start"]["yaw_deg"] = t.start->yaw_rad * 180.0 / M_PI;
  }
  v["time_limit_s"] = t.time_limit_s;
  Json::Value regions(Json::arrayValue), events(Json::arrayValue), comments(Json::objectValue);
  for (std::size_t i = 0; i < t.regions.size(); ++i) {
    Json::Value r;
    r["name"] = t.regions[i].name;
    r["min"] = xyz_json(t.regions[i].min_m);
    r["max"] = xyz_json(t.regions[i].max_m);
    r["comment"] = i < t.region_comments.size() ? t.region_comments[i] : "";
    regions.append(r);
  }
  for (const auto& e : t.events) events.append(event_json(e));
  for (const auto& [key, c] : t.key_comments) comments[key] = c;
  v["regions"] = regions;
  v["events"] = events;
  v["end_on"] = names_json(t.end_on);
  v["success"] = names_json(t.success);
  v["key_comments"] = comments;
  return v;
}

std::optional<tr::TaskDescription> task_from_json(const Json::Value& body, std::string* error) {
  if (!body.isObject()) return *error = "task: expected an object", std::nullopt;
  tr::TaskDescription t;
  if (!read_header(body, &t, error) || !read_key_comments(body["key_comments"], &t, error)) return std::nullopt;
  const Json::Value &regions = body["regions"], &events = body["events"];
  if (!regions.isNull() && (!regions.isArray() || regions.size() > kMaxEntries))
    return *error = "regions: expected a list (at most 500)", std::nullopt;
  if (!events.isArray() || events.size() > kMaxEntries) return *error = "events: expected a list (at most 500)", std::nullopt;
  for (Json::ArrayIndex i = 0; i < regions.size(); ++i)
    if (!read_region(regions[i], "regions[" + std::to_string(i) + "]", &t, error)) return std::nullopt;
  for (Json::ArrayIndex i = 0; i < events.size(); ++i) {
    tr::TaskEventSpec e;
    if (!read_event(events[i], "events[" + std::to_string(i) + "]", &e, error)) return std::nullopt;
    t.events.push_back(std::move(e));
  }
  return t;
}

Json::Value task_event_kinds_json() {
  Json::Value kinds(Json::arrayValue);
  for (const auto& k : tr::task_event_kinds()) {
    Json::Value j, params(Json::arrayValue);
    j["kind"] = k.name;
    j["what"] = k.what;
    j["default_max_count"] = k.default_max_count;
    for (const auto& p : k.params) {
      Json::Value q;
      q["key"] = p.key;
      q["type"] = p.type;
      q["required"] = p.required;
      q["what"] = p.what;
      params.append(q);
    }
    j["params"] = params;
    kinds.append(j);
  }
  return kinds;
}

TaskCheck check_task(const tr::TaskDescription& task, const std::string& path) {
  TaskCheck out;
  tr::TaskYamlLines lines;
  out.yaml = tr::write_task_description(task, &lines);
  try {
    // As rise-trainer check: the file, then its names against its world.
    const auto loaded = tr::parse_task_description(out.yaml, path);
    tr::check_against_world(loaded, sim::load_world_description(loaded.world_file));
  } catch (const std::exception& e) {
    for (auto& err : loader_errors(e.what(), path)) out.errors.push_back(with_entry(std::move(err), path, lines));
  }
  return out;
}

Json::Value check_json(const TaskCheck& check) { return check_json(check.yaml, check.errors); }

Json::Value task_files_json(const std::string& dir, const std::vector<std::string>& yaml_files) {
  static const std::regex task_key("(^|\n)task:");  // as rise-trainer check tells them apart
  Json::Value v, tasks(Json::arrayValue);
  v["dir"] = dir;
  for (const auto& file : yaml_files) {
    const std::string path = (fs::path(dir) / file).string();
    std::string text;
    try {
      text = panels::read_text_file(path);
    } catch (const std::exception&) {
      continue;
    }
    if (!std::regex_search(text, task_key)) continue;
    Json::Value t;
    t["file"] = file;
    try {
      const auto d = tr::parse_task_description(text, path);
      t["name"] = d.name;
      t["title"] = d.title;
    } catch (const std::exception& e) {
      t["error"] = e.what();
    }
    tasks.append(t);
  }
  v["tasks"] = tasks;
  v["kinds"] = task_event_kinds_json();
  return v;
}

}  // namespace rise::instructor
