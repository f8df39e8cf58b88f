#include "instructor/robot_builder.hpp"

#include "instructor/builder_errors.hpp"

#include <filesystem>
#include <regex>
#include <sstream>

#include "instructor/web_json.hpp"
#include "panels/yaml_reader.hpp"
#include "sim/urdf_tree.hpp"

namespace rise::instructor {
namespace fs = std::filesystem;

namespace {

constexpr std::size_t kMaxText = 10000;

Json::Value xyz(const std::array<double, 3>& p) {
  Json::Value v(Json::arrayValue);
  for (double c : p) v.append(c);
  return v;
}

const char* kind_name(sim::RobotKind k) {
  switch (k) {
    case sim::RobotKind::SkidSteer: return "skid_steer";
    case sim::RobotKind::Tracked: return "tracked";
    case sim::RobotKind::UrdfTree: return "urdf_tree";
  }
  return "";
}

// The `urdf:` value of a robot text, or "".
std::string urdf_name(const std::string& text) {
  try {
    for (const auto& s : sim::yaml_scalars(text))
      if (s.path == "urdf") return s.value;
  } catch (const std::exception&) {
  }
  return "";
}

// The line of `path`'s value in `text` (0 when it has none).
int line_of(const std::string& text, const std::string& path) {
  try {
    for (const auto& s : sim::yaml_scalars(text))
      if (s.path == path || s.path.rfind(path + ".", 0) == 0 || s.path.rfind(path + "[", 0) == 0) return s.line;
  } catch (const std::exception&) {
  }
  return 0;
}

Json::Value laser_json(const sim::LaserDescription& l) {
  Json::Value v;
  v["position"] = xyz(l.mount.position_m);
  v["rpy"] = xyz(l.mount.rpy_rad);
  v["fov"] = l.fov_rad;
  v["min_range"] = l.min_range_m;
  v["max_range"] = l.max_range_m;
  if (l.rotating) {
    v["rotating_axis"] = l.rotating->axis;
    v["sweep"] = l.rotating->sweep_rad;
  }
  return v;
}

// The URDF's tree for the view; a link without visuals drawn by its collision shapes.
std::optional<sim::UrdfTree> view_tree(const sim::RobotDescription& r, const std::string& urdf_path) {
  std::optional<sim::UrdfTree> tree = r.tree;
  if (!tree && !urdf_path.empty()) {
    try {
      tree = sim::read_urdf_tree(urdf_path);
    } catch (const std::exception&) {
      return std::nullopt;  // the loader took what it needs; the view draws the chassis box
    }
  }
  if (tree)
    for (auto& l : tree->links)
      if (l.visuals.empty()) l.visuals = l.collisions;
  return tree;
}

}  // namespace

std::optional<std::vector<sim::YamlEdit>> robot_edits_from_json(const Json::Value& edits, std::string* error) {
  if (!edits.isArray()) return *error = "edits: expected a list of {path, value}", std::nullopt;
  if (edits.size() > sim::kMaxYamlEdits) return *error = "edits: more than 1000", std::nullopt;
  std::vector<sim::YamlEdit> out;
  for (Json::ArrayIndex i = 0; i < edits.size(); ++i) {
    const std::string where = "edits[" + std::to_string(i) + "]";
    const Json::Value& e = edits[i];
    if (!e.isObject()) return *error = where + ": expected {path, value}", std::nullopt;
    const Json::Value &path = e["path"], &value = e["value"];
    if (!path.isString()) return *error = where + ".path: expected a string", std::nullopt;
    // Numbers as the page typed them: a JSON number's text is not (0.3 → 0.29999999999999999).
    if (!value.isString() && !value.isBool() && !(value.isIntegral() && !value.isDouble()))
      return *error = where + ".value: expected the value as a string (\"0.3\")", std::nullopt;
    sim::YamlEdit edit{path.asString(), value.asString()};
    if (edit.path.size() > 1000 || edit.value.size() > kMaxText)
      return *error = where + ": longer than 10000 characters", std::nullopt;
    if (edit.value.find('\0') != std::string::npos) return *error = where + ".value: contains NUL", std::nullopt;
    out.push_back(std::move(edit));
  }
  return out;
}

RobotCheck check_robot(const std::string& text, const std::vector<sim::YamlEdit>& edits, const std::string& path) {
  RobotCheck out;
  const std::string file = fs::path(path).filename().string();
  try {
    out.yaml = sim::apply_yaml_edits(text, edits);
  } catch (const sim::YamlEditError& e) {
    const std::string key = panels::printable(e.path()), what = e.what();  // "key: why"
    out.errors.push_back({file, line_of(text, e.path()), key, what.substr(key.size() + 2)});
    return out;
  } catch (const std::exception& e) {
    out.errors.push_back({file, 0, "", e.what()});
    return out;
  }
  try {
    out.robot = sim::parse_robot_description(out.yaml, path);
  } catch (const std::exception& e) {
    for (auto& err : loader_errors(e.what(), path, true)) out.errors.push_back(std::move(err));
  }
  return out;
}

Json::Value robot_scalars_json(const std::string& text) {
  Json::Value list(Json::arrayValue);
  try {
    for (const auto& s : sim::yaml_scalars(text)) {
      Json::Value v;
      v["path"] = s.path;
      v["value"] = s.value;
      v["line"] = s.line;
      list.append(v);
    }
  } catch (const std::exception&) {
  }
  return list;
}

Json::Value robot_check_json(const RobotCheck& check) {
  Json::Value v = check_json(check.yaml, check.errors);
  v["scalars"] = robot_scalars_json(check.yaml);
  if (check.robot) {
    const std::string urdf = urdf_name(check.yaml);
    v["robot"] = robot_view_json(*check.robot,
                                 urdf.empty() ? "" : (fs::path(check.robot->file).parent_path() / urdf).string());
  }
  return v;
}

Json::Value robot_view_json(const sim::RobotDescription& r, const std::string& urdf_path) {
  sim::RobotDescription drawn = r;
  drawn.tree = view_tree(r, urdf_path);
  Json::Value v = robot_json(drawn);  // name, chassis, cameras, links and joints
  v["kind"] = kind_name(r.kind);
  v["clearance"] = r.chassis.clearance_m;
  if (r.kind == sim::RobotKind::SkidSteer) {
    Json::Value w;
    w["radius"] = r.wheels.radius_m;
    w["width"] = r.wheels.width_m;
    w["wheelbase"] = r.wheels.wheelbase_m;
    w["track"] = r.wheels.track_m;
    v["wheels"] = w;
  }
  if (r.kind == sim::RobotKind::Tracked) {
    Json::Value t;
    t["length"] = r.tracks.length_m;
    t["radius"] = r.tracks.radius_m;
    t["gauge"] = r.tracks.gauge_m;
    t["approach"] = r.tracks.approach_rad;
    t["approach_length"] = r.tracks.approach_length_m;
    v["tracks"] = t;
  }
  if (r.sensors.laser) v["laser"] = laser_json(*r.sensors.laser);
  // The joints the panel drives, by URDF name, for the view to mark their axes.
  Json::Value driven(Json::arrayValue);
  for (const auto& j : r.control.joints) driven.append(j.joint);
  v["driven_joints"] = driven;
  return v;
}

Json::Value robot_files_json(const std::string& dir, const std::vector<std::string>& yaml_files) {
  Json::Value v, robots(Json::arrayValue);
  v["dir"] = dir;
  for (const auto& file : yaml_files) {
    Json::Value r;
    r["file"] = file;
    try {
      const auto d = sim::load_robot_description((fs::path(dir) / file).string());
      r["name"] = d.name;
      r["kind"] = kind_name(d.kind);
    } catch (const std::exception& e) {
      r["error"] = e.what();
    }
    robots.append(r);
  }
  v["robots"] = robots;
  return v;
}

}  // namespace rise::instructor
