#include "sim/world_description.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>

#include "panels/yaml_reader.hpp"

namespace rise::sim {

using panels::YamlReader;

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
  bool contains(const std::string& name) const { return names_.count(name) > 0; }

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

std::string metres(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

std::array<double, 3> sizes(const YamlReader& r, const YAML::Node& map, const std::string& where) {
  const auto size_m = r.vector<3>(map, "size_m", where);
  for (double s : size_m)
    if (!(s > 0)) r.fail(map["size_m"], where + ".size_m", "must be > 0");
  return size_m;
}

BoxObstacle read_box(const YamlReader& r, const YAML::Node& map, const std::string& where, Names& names) {
  BoxObstacle box;
  box.name = names.take(r, map, where);
  box.center_m = r.vector<3>(map, "center_m", where);
  box.size_m = sizes(r, map, where);
  box.yaw_rad = degrees(r, map, "yaw_deg", where, 0.0);
  return box;
}

std::vector<WallOpening> read_openings(const YamlReader& r, const YAML::Node& wall_node, const Wall& wall,
                                       const std::string& where) {
  std::vector<WallOpening> out;
  const YAML::Node list = wall_node["openings"];
  if (!list) return out;
  if (!list.IsSequence()) r.fail(list, where + ".openings", "expected a list");
  const double length_m = std::hypot(wall.to_m[0] - wall.from_m[0], wall.to_m[1] - wall.from_m[1]);
  for (std::size_t i = 0; i < list.size(); ++i) {
    const YAML::Node n = list[i];
    const std::string at = where + "." + item("openings", i);
    r.only_keys(n, at, {"at_m", "width_m", "height_m"});
    WallOpening o;
    if (!n["at_m"]) r.fail(n, at + ".at_m", "missing");
    o.at_m = r.positive(n, "at_m", at, o.at_m, true);
    o.width_m = r.positive(n, "width_m", at, o.width_m);
    o.height_m = r.positive(n, "height_m", at, o.height_m);
    if (o.at_m + o.width_m > length_m + 1e-9)
      r.fail(n, at, "outside the wall (" + metres(o.at_m) + ".." + metres(o.at_m + o.width_m) + " m along a " +
                        metres(length_m) + " m wall)");
    if (o.height_m > wall.height_m) r.fail(n["height_m"], at + ".height_m", "must be <= the wall's height");
    for (std::size_t j = 0; j < out.size(); ++j)
      if (o.at_m < out[j].at_m + out[j].width_m && out[j].at_m < o.at_m + o.width_m)
        r.fail(n, at, "overlaps " + item("openings", j));
    out.push_back(o);
  }
  std::sort(out.begin(), out.end(), [](const WallOpening& a, const WallOpening& b) { return a.at_m < b.at_m; });
  return out;
}

// Appends read(r, node, "key[i]", names) for each item of the list
// root[key], if there is one.
template <typename T, typename Read>
void read_list(const YamlReader& r, const YAML::Node& root, const char* key, Names& names, std::vector<T>& out,
               Read read) {
  if (const YAML::Node items = list(r, root, key))
    for (std::size_t i = 0; i < items.size(); ++i) out.push_back(read(r, items[i], item(key, i), names));
}

RobotStart read_robot_start(const YamlReader& r, const YAML::Node& s, const std::string& where) {
  r.only_keys(s, where, {"xy_m", "yaw_deg"});
  RobotStart start;
  start.xy_m = r.vector<2>(s, "xy_m", where);
  start.yaw_rad = degrees(r, s, "yaw_deg", where, 0.0);
  return start;
}

BoxObstacle read_listed_box(const YamlReader& r, const YAML::Node& n, const std::string& where, Names& names) {
  r.only_keys(n, where, {"name", "center_m", "size_m", "yaw_deg"});
  return read_box(r, n, where, names);
}

Prop read_prop(const YamlReader& r, const YAML::Node& n, const std::string& where, Names& names) {
  r.only_keys(n, where, {"name", "kind", "center_m", "size_m", "yaw_deg"});
  Prop p;
  p.box = read_box(r, n, where, names);
  if (!n["kind"]) r.fail(n, where + ".kind", "missing");
  p.kind = r.as<std::string>(n["kind"], where + ".kind");
  if (p.kind.empty()) r.fail(n["kind"], where + ".kind", "must not be empty");
  return p;
}

Wall read_wall(const YamlReader& r, const YAML::Node& n, const std::string& where, Names& names) {
  r.only_keys(n, where, {"name", "from", "to", "height", "thickness", "openings"});
  Wall wall;
  wall.name = names.take(r, n, where);
  wall.from_m = r.vector<2>(n, "from", where);
  wall.to_m = r.vector<2>(n, "to", where);
  wall.height_m = r.positive(n, "height", where, wall.height_m);
  wall.thickness_m = r.positive(n, "thickness", where, wall.thickness_m);
  if (std::hypot(wall.to_m[0] - wall.from_m[0], wall.to_m[1] - wall.from_m[1]) < 1e-3)
    r.fail(n["to"], where + ".to", "must differ from 'from'");
  wall.openings = read_openings(r, n, wall, where);
  return wall;
}

Door read_door(const YamlReader& r, const YAML::Node& n, const std::string& where, Names& names) {
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
  return d;
}

Stairs read_stairs(const YamlReader& r, const YAML::Node& n, const std::string& where, Names& names) {
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
  return s;
}

MovableObject read_object(const YamlReader& r, const YAML::Node& n, const std::string& where, Names& names) {
  r.only_keys(n, where, {"name", "size_m", "mass_kg", "center_m"});
  MovableObject o;
  o.name = names.take(r, n, where);
  o.size_m = sizes(r, n, where);
  if (!n["mass_kg"]) r.fail(n, where + ".mass_kg", "missing");
  o.mass_kg = r.positive(n, "mass_kg", where, o.mass_kg);
  o.center_m = r.vector<3>(n, "center_m", where);
  return o;
}

Region read_region(const YamlReader& r, const YAML::Node& n, const std::string& where, Names& names) {
  r.only_keys(n, where, {"name", "min", "max"});
  Region g;
  g.name = names.take(r, n, where);
  g.min_m = r.vector<3>(n, "min", where);
  g.max_m = r.vector<3>(n, "max", where);
  for (std::size_t k = 0; k < 3; ++k)
    if (!(g.max_m[k] > g.min_m[k])) r.fail(n["max"], where + ".max", "must exceed min on every axis");
  return g;
}

Ceiling read_ceiling(const YamlReader& r, const YAML::Node& n, const WorldDescription& w, const Names& names) {
  r.only_keys(n, "ceiling", {"height_m", "thickness_m", "min", "max"});
  Ceiling c;
  if (!n["height_m"]) r.fail(n, "ceiling.height_m", "missing");
  c.height_m = r.positive(n, "height_m", "ceiling", c.height_m);
  c.thickness_m = r.positive(n, "thickness_m", "ceiling", c.thickness_m);
  if (names.contains("ceiling")) r.fail(n, "ceiling", "another entity is named 'ceiling'");
  if (n["min"] || n["max"]) {
    if (!n["min"] || !n["max"]) r.fail(n, "ceiling", "give both min and max, or neither");
    c.min_m = r.vector<2>(n, "min", "ceiling");
    c.max_m = r.vector<2>(n, "max", "ceiling");
    for (std::size_t k = 0; k < 2; ++k)
      if (!(c.max_m[k] > c.min_m[k])) r.fail(n["max"], "ceiling.max", "must exceed min on x and y");
    return c;
  }
  if (w.walls.empty()) r.fail(n, "ceiling", "needs min and max in a world without walls");
  // Over the walls' end points, widened by half their thickness: for walls
  // along x or y exactly the outline of their (lengthened) boxes.
  c.min_m = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  c.max_m = {-c.min_m[0], -c.min_m[1]};
  for (const auto& wall : w.walls)
    for (const auto& p : {wall.from_m, wall.to_m})
      for (std::size_t k = 0; k < 2; ++k) {
        c.min_m[k] = std::min(c.min_m[k], p[k] - wall.thickness_m / 2);
        c.max_m[k] = std::max(c.max_m[k], p[k] + wall.thickness_m / 2);
      }
  return c;
}

}  // namespace

std::vector<BoxObstacle> wall_boxes(const Wall& wall) {
  const double dx = wall.to_m[0] - wall.from_m[0], dy = wall.to_m[1] - wall.from_m[1];
  const double length_m = std::hypot(dx, dy), yaw_rad = std::atan2(dy, dx);
  std::vector<BoxObstacle> out;
  // The box spanning [along0, along1] metres along the wall from `from` and z0..z1.
  const auto piece = [&](double along0, double along1, double z0, double z1) {
    if (!(along1 - along0 > 1e-9) || !(z1 - z0 > 1e-9)) return;
    const double along = (along0 + along1) / 2;
    out.push_back({wall.name,
                   {wall.from_m[0] + dx / length_m * along, wall.from_m[1] + dy / length_m * along, (z0 + z1) / 2},
                   {along1 - along0, wall.thickness_m, z1 - z0},
                   yaw_rad});
  };
  double start = -wall.thickness_m / 2;
  for (const auto& o : wall.openings) {
    piece(start, o.at_m, 0.0, wall.height_m);
    piece(o.at_m, o.at_m + o.width_m, o.height_m, wall.height_m);  // the lintel
    start = o.at_m + o.width_m;
  }
  piece(start, length_m + wall.thickness_m / 2, 0.0, wall.height_m);
  return out;
}

BoxObstacle ceiling_box(const Ceiling& c) {
  return {"ceiling",
          {(c.min_m[0] + c.max_m[0]) / 2, (c.min_m[1] + c.max_m[1]) / 2, c.height_m + c.thickness_m / 2},
          {c.max_m[0] - c.min_m[0], c.max_m[1] - c.min_m[1], c.thickness_m},
          0.0};
}

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
  r.only_keys(root, "", {"world", "ground", "robot_start", "robot_starts", "ceiling", "boxes", "props", "walls", "doors", "stairs", "objects", "regions"});
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
  read_list(r, root, "robot_starts", names, w.robot_starts,
            [](const YamlReader& rr, const YAML::Node& n, const std::string& where, Names&) {
              return read_robot_start(rr, n, where);
            });
  read_list(r, root, "boxes", names, w.boxes, read_listed_box);
  read_list(r, root, "props", names, w.props, read_prop);
  read_list(r, root, "walls", names, w.walls, read_wall);
  read_list(r, root, "doors", names, w.doors, read_door);
  read_list(r, root, "stairs", names, w.stairs, read_stairs);
  read_list(r, root, "objects", names, w.objects, read_object);
  read_list(r, root, "regions", names, w.regions, read_region);
  if (const YAML::Node c = root["ceiling"]) w.ceiling = read_ceiling(r, c, w, names);
  return w;
}

WorldDescription load_world_description(const std::string& path) {
  return parse_world_description(panels::read_text_file(path), path);
}

}  // namespace rise::sim
