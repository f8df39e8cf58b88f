#include "sim/world_description.hpp"

#include <cmath>
#include <set>

#include "sim/yaml_reader.hpp"

namespace rise::sim {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

// Every entity has a unique name: events and contacts name them.
class Names {
 public:
  std::string take(const YamlReader& r, const YAML::Node& map, const std::string& where) {
    if (!map["name"]) r.fail(map, where + ".name", "missing");
    auto name = r.as<std::string>(map["name"], where + ".name");
    if (name.empty()) r.fail(map["name"], where + ".name", "must not be empty");
    if (!names_.insert(name).second) r.fail(map["name"], where + ".name", "duplicate name '" + name + "'");
    return name;
  }

 private:
  std::set<std::string> names_;
};

const YAML::Node list(const YamlReader& r, const YAML::Node& root, const char* key) {
  const YAML::Node l = root[key];
  if (l && !l.IsSequence()) r.fail(l, key, "expected a list");
  return l;
}

std::string item(const char* key, std::size_t i) { return std::string(key) + "[" + std::to_string(i) + "]"; }

double degrees(const YamlReader& r, const YAML::Node& map, const char* key, const std::string& where, double fallback) {
  if (!map[key]) return fallback;
  return r.as<double>(map[key], where + "." + key) * kDegToRad;
}

}  // namespace

WorldDescription default_world() {
  WorldDescription w;
  w.name = "yard";
  // A few obstacles beside the start, clear of the demo's drive (ahead, then
  // a right curve), and a wall far ahead.
  w.boxes.push_back({"crate_a", {-3.0, 3.0, 0.3}, {0.6, 0.6, 0.6}, 0.0});
  w.boxes.push_back({"crate_b", {-4.0, -3.0, 0.4}, {0.8, 0.8, 0.8}, 0.4});
  w.boxes.push_back({"barrier", {0.0, -4.0, 0.25}, {2.0, 0.2, 0.5}, 0.0});
  w.boxes.push_back({"wall_north", {25.0, 0.0, 1.0}, {0.3, 20.0, 2.0}, 0.0});
  return w;
}

WorldDescription parse_world_description(const std::string& text, const std::string& file) {
  const YamlReader r(file);
  const YAML::Node root = r.load_text(text);
  if (!root.IsMap()) r.fail(root, "", "expected a mapping with world, ground, boxes, ...");
  r.only_keys(root, "", {"world", "ground", "robot_start", "boxes", "walls", "doors", "stairs", "objects", "regions"});
  WorldDescription w;
  w.file = file;
  Names names;
  if (root["world"]) w.name = r.as<std::string>(root["world"], "world");
  if (const YAML::Node g = root["ground"]) {
    r.only_keys(g, "ground", {"friction"});
    w.ground_friction = r.positive(g, "friction", "ground", w.ground_friction);
  }
  if (const YAML::Node s = root["robot_start"]) {
    r.only_keys(s, "robot_start", {"xy_m", "yaw_deg"});
    if (s["xy_m"]) w.robot_start_m = r.vector<2>(s, "xy_m", "robot_start");
    w.robot_start_yaw_rad = degrees(r, s, "yaw_deg", "robot_start", 0.0);
  }
  if (const YAML::Node boxes = list(r, root, "boxes")) {
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      const YAML::Node b = boxes[i];
      const std::string where = item("boxes", i);
      r.only_keys(b, where, {"name", "center_m", "size_m", "yaw_deg"});
      BoxObstacle box;
      box.name = names.take(r, b, where);
      box.center_m = r.vector<3>(b, "center_m", where);
      box.size_m = r.vector<3>(b, "size_m", where);
      for (double s : box.size_m)
        if (!(s > 0)) r.fail(b["size_m"], where + ".size_m", "must be > 0");
      box.yaw_rad = degrees(r, b, "yaw_deg", where, 0.0);
      w.boxes.push_back(box);
    }
  }
  if (const YAML::Node walls = list(r, root, "walls")) {
    for (std::size_t i = 0; i < walls.size(); ++i) {
      const YAML::Node n = walls[i];
      const std::string where = item("walls", i);
      r.only_keys(n, where, {"name", "from", "to", "height", "thickness"});
      Wall wall;
      wall.name = names.take(r, n, where);
      wall.from_m = r.vector<2>(n, "from", where);
      wall.to_m = r.vector<2>(n, "to", where);
      wall.height_m = r.positive(n, "height", where, wall.height_m);
      wall.thickness_m = r.positive(n, "thickness", where, wall.thickness_m);
      if (std::hypot(wall.to_m[0] - wall.from_m[0], wall.to_m[1] - wall.from_m[1]) < 1e-3)
        r.fail(n["to"], where + ".to", "must differ from 'from'");
      w.walls.push_back(wall);
    }
  }
  if (const YAML::Node doors = list(r, root, "doors")) {
    for (std::size_t i = 0; i < doors.size(); ++i) {
      const YAML::Node n = doors[i];
      const std::string where = item("doors", i);
      r.only_keys(n, where, {"name", "hinge", "width", "height", "thickness", "yaw_deg", "open_deg_max",
                             "break_torque_nm", "break_time_ms", "mass_kg", "friction_torque_nm", "return_nm_per_rad"});
      Door d;
      d.name = names.take(r, n, where);
      d.hinge_m = r.vector<2>(n, "hinge", where);
      d.width_m = r.positive(n, "width", where, d.width_m);
      d.height_m = r.positive(n, "height", where, d.height_m);
      d.thickness_m = r.positive(n, "thickness", where, d.thickness_m);
      d.yaw_rad = degrees(r, n, "yaw_deg", where, 0.0);
      d.open_max_rad = r.positive(n, "open_deg_max", where, d.open_max_rad / kDegToRad) * kDegToRad;
      if (d.open_max_rad > M_PI) r.fail(n["open_deg_max"], where + ".open_deg_max", "must be <= 180");
      d.break_torque_nm = r.positive(n, "break_torque_nm", where, d.break_torque_nm);
      d.break_time_ms = r.positive(n, "break_time_ms", where, d.break_time_ms);
      d.mass_kg = r.positive(n, "mass_kg", where, d.mass_kg);
      d.friction_torque_nm = r.positive(n, "friction_torque_nm", where, d.friction_torque_nm, true);
      d.return_nm_per_rad = r.positive(n, "return_nm_per_rad", where, d.return_nm_per_rad, true);
      w.doors.push_back(d);
    }
  }
  if (const YAML::Node stairs = list(r, root, "stairs")) {
    for (std::size_t i = 0; i < stairs.size(); ++i) {
      const YAML::Node n = stairs[i];
      const std::string where = item("stairs", i);
      r.only_keys(n, where, {"name", "start", "yaw_deg", "steps", "riser_m", "tread_m", "width_m", "landing_m"});
      Stairs s;
      s.name = names.take(r, n, where);
      s.start_m = r.vector<2>(n, "start", where);
      s.yaw_rad = degrees(r, n, "yaw_deg", where, 0.0);
      if (n["steps"]) {
        s.steps = r.as<int>(n["steps"], where + ".steps");
        if (s.steps < 1 || s.steps > 100) r.fail(n["steps"], where + ".steps", "must be in 1..100");
      }
      s.riser_m = r.positive(n, "riser_m", where, s.riser_m);
      s.tread_m = r.positive(n, "tread_m", where, s.tread_m);
      s.width_m = r.positive(n, "width_m", where, s.width_m);
      s.landing_m = r.positive(n, "landing_m", where, s.landing_m);
      w.stairs.push_back(s);
    }
  }
  if (const YAML::Node objects = list(r, root, "objects")) {
    for (std::size_t i = 0; i < objects.size(); ++i) {
      const YAML::Node n = objects[i];
      const std::string where = item("objects", i);
      r.only_keys(n, where, {"name", "size_m", "mass_kg", "center_m"});
      MovableObject o;
      o.name = names.take(r, n, where);
      o.size_m = r.vector<3>(n, "size_m", where);
      for (double s : o.size_m)
        if (!(s > 0)) r.fail(n["size_m"], where + ".size_m", "must be > 0");
      if (!n["mass_kg"]) r.fail(n, where + ".mass_kg", "missing");
      o.mass_kg = r.positive(n, "mass_kg", where, o.mass_kg);
      o.center_m = r.vector<3>(n, "center_m", where);
      w.objects.push_back(o);
    }
  }
  if (const YAML::Node regions = list(r, root, "regions")) {
    for (std::size_t i = 0; i < regions.size(); ++i) {
      const YAML::Node n = regions[i];
      const std::string where = item("regions", i);
      r.only_keys(n, where, {"name", "min", "max"});
      Region g;
      g.name = names.take(r, n, where);
      g.min_m = r.vector<3>(n, "min", where);
      g.max_m = r.vector<3>(n, "max", where);
      for (std::size_t k = 0; k < 3; ++k)
        if (!(g.max_m[k] > g.min_m[k])) r.fail(n["max"], where + ".max", "must exceed min on every axis");
      w.regions.push_back(g);
    }
  }
  return w;
}

WorldDescription load_world_description(const std::string& path) {
  return parse_world_description(read_text_file(path), path);
}

}  // namespace rise::sim
