#include "instructor/world_builder.hpp"

#include "instructor/builder_errors.hpp"

#include <cmath>
#include <filesystem>
#include <memory>
#include <regex>
#include <stdexcept>

#include "panels/yaml_reader.hpp"
#include "sim/world_writer.hpp"

namespace rise::instructor {
namespace fs = std::filesystem;

namespace {

constexpr double kDegToRad = M_PI / 180.0;  // as the loader converts
constexpr Json::ArrayIndex kMaxEntries = 5000;
constexpr std::size_t kMaxText = 200;

// ---- the model as JSON -------------------------------------------------------

Json::Value numbers(const double* v, std::size_t n) {
  Json::Value a(Json::arrayValue);
  for (std::size_t i = 0; i < n; ++i) a.append(v[i]);
  return a;
}
template <std::size_t N>
Json::Value numbers(const std::array<double, N>& v) {
  return numbers(v.data(), N);
}

Json::Value deg(double rad) { return sim::degrees_as_written(rad); }

Json::Value box_json(const sim::BoxObstacle& b) {
  Json::Value j;
  j["name"] = b.name;
  j["center_m"] = numbers(b.center_m);
  j["size_m"] = numbers(b.size_m);
  j["yaw_deg"] = deg(b.yaw_rad);
  return j;
}

Json::Value wall_json(const sim::Wall& w) {
  Json::Value j, openings(Json::arrayValue);
  j["name"] = w.name;
  j["from"] = numbers(w.from_m);
  j["to"] = numbers(w.to_m);
  j["height"] = w.height_m;
  j["thickness"] = w.thickness_m;
  for (const auto& o : w.openings) {
    Json::Value x;
    x["at_m"] = o.at_m;
    x["width_m"] = o.width_m;
    x["height_m"] = o.height_m;
    openings.append(x);
  }
  j["openings"] = openings;
  return j;
}

Json::Value door_json(const sim::Door& d) {
  Json::Value j;
  j["name"] = d.name;
  j["hinge"] = numbers(d.hinge_m);
  j["width"] = d.width_m;
  j["height"] = d.height_m;
  j["thickness"] = d.thickness_m;
  j["yaw_deg"] = deg(d.yaw_rad);
  j["open_deg_max"] = deg(d.open_max_rad);
  j["break_torque_nm"] = d.break_torque_nm;
  j["break_time_ms"] = d.break_time_ms;
  j["mass_kg"] = d.mass_kg;
  j["friction_torque_nm"] = d.friction_torque_nm;
  j["return_nm_per_rad"] = d.return_nm_per_rad;
  return j;
}

Json::Value stairs_json(const sim::Stairs& s) {
  Json::Value j;
  j["name"] = s.name;
  j["start"] = numbers(s.start_m);
  j["yaw_deg"] = deg(s.yaw_rad);
  j["steps"] = s.steps;
  j["riser_m"] = s.riser_m;
  j["tread_m"] = s.tread_m;
  j["width_m"] = s.width_m;
  j["landing_m"] = s.landing_m;
  return j;
}

template <typename T, typename F>
Json::Value list_json(const std::vector<T>& items, F f) {
  Json::Value a(Json::arrayValue);
  for (const auto& i : items) a.append(f(i));
  return a;
}

// ---- the page's JSON as a model (untrusted) ----------------------------------

struct Shape : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::string at(const std::string& where, const char* key) { return where.empty() ? key : where + "." + key; }

double number(const Json::Value& o, const char* key, const std::string& where) {
  const Json::Value& v = o[key];
  if (!v.isNumeric()) throw Shape(at(where, key) + ": expected a number");
  return v.asDouble();
}

double number_or(const Json::Value& o, const char* key, const std::string& where, double fallback) {
  return o[key].isNull() ? fallback : number(o, key, where);
}

template <std::size_t N>
std::array<double, N> numbers_of(const Json::Value& o, const char* key, const std::string& where) {
  const Json::Value& v = o[key];
  if (!v.isArray() || v.size() != N) throw Shape(at(where, key) + ": expected " + std::to_string(N) + " numbers");
  std::array<double, N> out{};
  for (Json::ArrayIndex i = 0; i < N; ++i) {
    if (!v[i].isNumeric()) throw Shape(at(where, key) + ": expected " + std::to_string(N) + " numbers");
    out[i] = v[i].asDouble();
  }
  return out;
}

std::string text(const Json::Value& o, const char* key, const std::string& where) {
  const Json::Value& v = o[key];
  if (!v.isString()) throw Shape(at(where, key) + ": expected a string");
  std::string s = v.asString();
  if (s.size() > kMaxText) throw Shape(at(where, key) + ": longer than 200 characters");
  if (s.find('\0') != std::string::npos) throw Shape(at(where, key) + ": contains NUL");
  return s;
}

sim::BoxObstacle box_of(const Json::Value& j, const std::string& where) {
  sim::BoxObstacle b;
  b.name = text(j, "name", where);
  b.center_m = numbers_of<3>(j, "center_m", where);
  b.size_m = numbers_of<3>(j, "size_m", where);
  b.yaw_rad = number_or(j, "yaw_deg", where, 0.0) * kDegToRad;
  return b;
}

sim::Wall wall_of(const Json::Value& j, const std::string& where) {
  sim::Wall w;
  w.name = text(j, "name", where);
  w.from_m = numbers_of<2>(j, "from", where);
  w.to_m = numbers_of<2>(j, "to", where);
  w.height_m = number_or(j, "height", where, w.height_m);
  w.thickness_m = number_or(j, "thickness", where, w.thickness_m);
  const Json::Value& os = j["openings"];
  if (!os.isNull() && !os.isArray()) throw Shape(where + ".openings: expected a list");
  for (Json::ArrayIndex i = 0; i < os.size() && i < 100; ++i) {
    const std::string w_at = where + ".openings[" + std::to_string(i) + "]";
    if (!os[i].isObject()) throw Shape(w_at + ": expected an object");
    sim::WallOpening o;
    o.at_m = number(os[i], "at_m", w_at);
    o.width_m = number_or(os[i], "width_m", w_at, o.width_m);
    o.height_m = number_or(os[i], "height_m", w_at, o.height_m);
    w.openings.push_back(o);
  }
  return w;
}

sim::Door door_of(const Json::Value& j, const std::string& where) {
  sim::Door d;
  d.name = text(j, "name", where);
  d.hinge_m = numbers_of<2>(j, "hinge", where);
  d.width_m = number_or(j, "width", where, d.width_m);
  d.height_m = number_or(j, "height", where, d.height_m);
  d.thickness_m = number_or(j, "thickness", where, d.thickness_m);
  d.yaw_rad = number_or(j, "yaw_deg", where, 0.0) * kDegToRad;
  d.open_max_rad = number_or(j, "open_deg_max", where, d.open_max_rad / kDegToRad) * kDegToRad;
  d.break_torque_nm = number_or(j, "break_torque_nm", where, d.break_torque_nm);
  d.break_time_ms = number_or(j, "break_time_ms", where, d.break_time_ms);
  d.mass_kg = number_or(j, "mass_kg", where, d.mass_kg);
  d.friction_torque_nm = number_or(j, "friction_torque_nm", where, d.friction_torque_nm);
  d.return_nm_per_rad = number_or(j, "return_nm_per_rad", where, d.return_nm_per_rad);
  return d;
}

sim::Stairs stairs_of(const Json::Value& j, const std::string& where) {
  sim::Stairs s;
  s.name = text(j, "name", where);
  s.start_m = numbers_of<2>(j, "start", where);
  s.yaw_rad = number_or(j, "yaw_deg", where, 0.0) * kDegToRad;
  const double steps = number_or(j, "steps", where, s.steps);
  if (steps != std::floor(steps) || std::fabs(steps) > 1e6) throw Shape(where + ".steps: expected a whole number");
  s.steps = static_cast<int>(steps);  // out of 1..100: the loader names it with its line
  s.riser_m = number_or(j, "riser_m", where, s.riser_m);
  s.tread_m = number_or(j, "tread_m", where, s.tread_m);
  s.width_m = number_or(j, "width_m", where, s.width_m);
  s.landing_m = number_or(j, "landing_m", where, s.landing_m);
  return s;
}

sim::MovableObject object_of(const Json::Value& j, const std::string& where) {
  sim::MovableObject o;
  o.name = text(j, "name", where);
  o.size_m = numbers_of<3>(j, "size_m", where);
  o.mass_kg = number(j, "mass_kg", where);
  o.center_m = numbers_of<3>(j, "center_m", where);
  return o;
}

sim::Region region_of(const Json::Value& j, const std::string& where) {
  sim::Region g;
  g.name = text(j, "name", where);
  g.min_m = numbers_of<3>(j, "min", where);
  g.max_m = numbers_of<3>(j, "max", where);
  return g;
}

sim::RobotStart start_of(const Json::Value& j, const std::string& where) {
  sim::RobotStart s;
  s.xy_m = numbers_of<2>(j, "xy_m", where);
  s.yaw_rad = number_or(j, "yaw_deg", where, 0.0) * kDegToRad;
  return s;
}

template <typename T, typename F>
void read_entries(const Json::Value& body, const char* key, std::vector<T>& out, F read) {
  const Json::Value& l = body[key];
  if (l.isNull()) return;
  if (!l.isArray() || l.size() > kMaxEntries) throw Shape(std::string(key) + ": expected a list (at most 5000)");
  for (Json::ArrayIndex i = 0; i < l.size(); ++i) {
    const std::string where = std::string(key) + "[" + std::to_string(i) + "]";
    if (!l[i].isObject()) throw Shape(where + ": expected an object");
    out.push_back(read(l[i], where));
  }
}

sim::WorldDescription world_of(const Json::Value& body) {
  if (!body.isObject()) throw Shape("world: expected an object");
  sim::WorldDescription w;
  w.boxes.clear();
  w.name = text(body, "world", "");
  w.ground_friction = number_or(body, "ground_friction", "", w.ground_friction);
  if (body["robot_start"].isObject()) {
    const auto s = start_of(body["robot_start"], "robot_start");
    w.robot_start_m = s.xy_m;
    w.robot_start_yaw_rad = s.yaw_rad;
  }
  read_entries(body, "robot_starts", w.robot_starts, start_of);
  read_entries(body, "boxes", w.boxes, box_of);
  read_entries(body, "props", w.props, [](const Json::Value& j, const std::string& where) {
    return sim::Prop{box_of(j, where), text(j, "kind", where)};
  });
  read_entries(body, "walls", w.walls, wall_of);
  read_entries(body, "doors", w.doors, door_of);
  read_entries(body, "stairs", w.stairs, stairs_of);
  read_entries(body, "objects", w.objects, object_of);
  read_entries(body, "regions", w.regions, region_of);
  if (const Json::Value& c = body["ceiling"]; c.isObject()) {
    sim::Ceiling ceiling;
    if (!c["follows_walls"].isNull() && !c["follows_walls"].isBool())
      throw Shape("ceiling.follows_walls: expected true or false");
    ceiling.height_m = number(c, "height_m", "ceiling");
    ceiling.thickness_m = number_or(c, "thickness_m", "ceiling", ceiling.thickness_m);
    if (!c["follows_walls"].asBool()) {
      ceiling.min_m = numbers_of<2>(c, "min", "ceiling");
      ceiling.max_m = numbers_of<2>(c, "max", "ceiling");
    }
    w.ceiling = ceiling;
    if (c["follows_walls"].asBool()) sim::fit_ceiling_to_walls(w);
  } else if (!c.isNull()) {
    throw Shape("ceiling: expected an object or null");
  }
  return w;
}

// ---- the loader's error ------------------------------------------------------

}  // namespace

Json::Value world_model_json(const sim::WorldDescription& w) {
  Json::Value v;
  v["world"] = w.name;
  v["ground_friction"] = w.ground_friction;
  Json::Value start;
  start["xy_m"] = numbers(w.robot_start_m);
  start["yaw_deg"] = deg(w.robot_start_yaw_rad);
  v["robot_start"] = start;
  v["robot_starts"] = list_json(w.robot_starts, [](const sim::RobotStart& s) {
    Json::Value j;
    j["xy_m"] = numbers(s.xy_m);
    j["yaw_deg"] = deg(s.yaw_rad);
    return j;
  });
  v["boxes"] = list_json(w.boxes, box_json);
  v["props"] = list_json(w.props, [](const sim::Prop& p) {
    Json::Value j = box_json(p.box);
    j["kind"] = p.kind;
    return j;
  });
  v["walls"] = list_json(w.walls, wall_json);
  v["doors"] = list_json(w.doors, door_json);
  v["stairs"] = list_json(w.stairs, stairs_json);
  v["objects"] = list_json(w.objects, [](const sim::MovableObject& o) {
    Json::Value j;
    j["name"] = o.name;
    j["size_m"] = numbers(o.size_m);
    j["mass_kg"] = o.mass_kg;
    j["center_m"] = numbers(o.center_m);
    return j;
  });
  v["regions"] = list_json(w.regions, [](const sim::Region& g) {
    Json::Value j;
    j["name"] = g.name;
    j["min"] = numbers(g.min_m);
    j["max"] = numbers(g.max_m);
    return j;
  });
  if (w.ceiling) {
    Json::Value c;
    c["height_m"] = w.ceiling->height_m;
    c["thickness_m"] = w.ceiling->thickness_m;
    c["min"] = numbers(w.ceiling->min_m);
    c["max"] = numbers(w.ceiling->max_m);
    c["follows_walls"] = sim::ceiling_follows_walls(w);
    v["ceiling"] = c;
  } else {
    v["ceiling"] = Json::Value();
  }
  return v;
}

std::optional<sim::WorldDescription> world_model_from_json(const Json::Value& body, std::string* error) {
  try {
    return world_of(body);
  } catch (const Shape& e) {
    *error = e.what();
    return std::nullopt;
  }
}

WorldCheck check_world(const sim::WorldDescription& world, const std::string& path, const std::string& disk) {
  WorldCheck out;
  out.yaml = sim::write_world(world, sim::read_world_comments(disk));
  try {
    out.loaded = sim::parse_world_description(out.yaml, path);
  } catch (const std::exception& e) {
    out.errors.push_back(loader_error(e.what(), path));
  }
  return out;
}

}  // namespace rise::instructor
