#include "sim/world_writer.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <sstream>
#include <tuple>
#include <utility>
#include <vector>

#include "panels/yaml_writer.hpp"

namespace rise::sim {

namespace {

constexpr double kDegToRad = M_PI / 180.0;  // as the loader converts (world_description.cpp)
const char* const kLists[] = {"robot_starts", "boxes", "props", "walls", "doors", "stairs", "objects", "regions"};

// ---- numbers ---------------------------------------------------------------

// The shortest decimal of `v` for which `same` holds (it reads back as the
// value written), without an exponent where that stays short.
std::string shortest(double v, const std::function<bool(double)>& same) {
  char buf[64];
  for (int d = 0; d <= 17; ++d) {
    std::snprintf(buf, sizeof buf, "%.*f", d, v);
    if (same(std::strtod(buf, nullptr)) && std::string(buf).size() <= 24) return buf;
  }
  for (int p = 1; p <= 17; ++p) {
    std::snprintf(buf, sizeof buf, "%.*g", p, v);
    if (same(std::strtod(buf, nullptr))) return buf;
  }
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string num(double v) {
  // YAML's own words for what is no finite number (a loaded .nan centre).
  if (std::isnan(v)) return ".nan";
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  return shortest(v, [v](double x) { return x == v; });
}

// Radians as the degrees the loader turns back into the same radians.
std::string deg(double rad) {
  if (!std::isfinite(rad)) return num(rad);
  return shortest(rad / kDegToRad, [rad](double x) { return x * kDegToRad == rad; });
}

template <std::size_t N>
std::string vec(const std::array<double, N>& a) {
  std::string out = "[";
  for (std::size_t i = 0; i < N; ++i) out += (i ? ", " : "") + num(a[i]);
  return out + "]";
}

// ---- strings ---------------------------------------------------------------

std::string str(const std::string& text) { return panels::yaml_string(text); }

// ---- comments --------------------------------------------------------------

// The text after a '#' that starts a comment on `line` (outside quotes,
// at the start or after a blank), or "".
std::string trailing_comment(const std::string& line) {
  const std::size_t hash = panels::yaml_comment_start(line);
  if (hash == std::string::npos) return "";
  const std::string t = line.substr(hash + 1);
  const auto a = t.find_first_not_of(' '), b = t.find_last_not_of(" \r");
  return a == std::string::npos ? "" : t.substr(a, b - a + 1);
}

// A line as written back: no control characters but tabs (a CR inside a
// line would start another one).
std::string clean(std::string line) {
  if (!line.empty() && line.back() == '\r') line.pop_back();
  for (char& c : line)
    if ((static_cast<unsigned char>(c) < 0x20 && c != '\t') || c == 0x7f) c = ' ';
  return line;
}

bool blank_or_comment(const std::string& line) {
  const auto a = line.find_first_not_of(" \t\r");
  return a == std::string::npos || line[a] == '#';
}

// Line (0-based) → what starts there: "walls" or "entry:NAME" or "robot_starts[2]".
std::map<int, std::string> anchors(const YAML::Node& root) {
  std::map<int, std::string> out;
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>("");
    out[kv.first.Mark().line] = key;
    if (!kv.second.IsSequence()) continue;
    for (std::size_t i = 0; i < kv.second.size(); ++i) {
      const YAML::Node item = kv.second[i];
      std::string name;
      if (item.IsMap() && item["name"] && item["name"].IsScalar()) name = "entry:" + item["name"].as<std::string>();
      else if (key == "robot_starts") name = key + "[" + std::to_string(i) + "]";
      if (!name.empty() && item.Mark().line >= 0) out[item.Mark().line] = name;
    }
  }
  return out;
}

// ---- writing ---------------------------------------------------------------

class Out {
 public:
  explicit Out(const WorldComments& c) : c_(c) {}
  // `line` for `anchor`, with the comment block above it and its line's comment.
  void add(const std::string& anchor, const std::string& line) {
    if (const auto a = c_.above.find(anchor); a != c_.above.end()) text_ += a->second;
    text_ += line;
    if (const auto t = c_.trailing.find(anchor); t != c_.trailing.end() && !t->second.empty()) text_ += "  # " + t->second;
    text_ += "\n";
  }
  std::string finish() { return text_ + c_.end; }

 private:
  const WorldComments& c_;
  std::string text_;
};

// "{k: v, ...}" of the fields in order.
std::string flow(const std::vector<std::pair<std::string, std::string>>& fields) {
  std::string out = "{";
  for (std::size_t i = 0; i < fields.size(); ++i) out += (i ? ", " : "") + fields[i].first + ": " + fields[i].second;
  return out + "}";
}

using Fields = std::vector<std::pair<std::string, std::string>>;

std::string box_entry(const BoxObstacle& b, const std::string* kind) {
  Fields f{{"name", str(b.name)}};
  if (kind) f.emplace_back("kind", str(*kind));
  f.emplace_back("center_m", vec(b.center_m));
  f.emplace_back("size_m", vec(b.size_m));
  if (b.yaw_rad != 0.0) f.emplace_back("yaw_deg", deg(b.yaw_rad));
  return flow(f);
}

std::string wall_entry(const Wall& w) {
  Fields f{{"name", str(w.name)}, {"from", vec(w.from_m)}, {"to", vec(w.to_m)}, {"height", num(w.height_m)},
           {"thickness", num(w.thickness_m)}};
  if (!w.openings.empty()) {
    std::string list = "[";
    for (std::size_t i = 0; i < w.openings.size(); ++i) {
      const auto& o = w.openings[i];
      list += (i ? ", " : "") +
              flow({{"at_m", num(o.at_m)}, {"width_m", num(o.width_m)}, {"height_m", num(o.height_m)}});
    }
    f.emplace_back("openings", list + "]");
  }
  return flow(f);
}

std::string door_entry(const Door& d) {
  const Door def;
  Fields f{{"name", str(d.name)},       {"hinge", vec(d.hinge_m)},          {"width", num(d.width_m)},
           {"height", num(d.height_m)}, {"thickness", num(d.thickness_m)}, {"yaw_deg", deg(d.yaw_rad)},
           {"open_deg_max", deg(d.open_max_rad)}, {"break_torque_nm", num(d.break_torque_nm)}};
  if (d.break_time_ms != def.break_time_ms) f.emplace_back("break_time_ms", num(d.break_time_ms));
  f.emplace_back("mass_kg", num(d.mass_kg));
  if (d.friction_torque_nm != def.friction_torque_nm) f.emplace_back("friction_torque_nm", num(d.friction_torque_nm));
  if (d.return_nm_per_rad != def.return_nm_per_rad) f.emplace_back("return_nm_per_rad", num(d.return_nm_per_rad));
  return flow(f);
}

std::string stairs_entry(const Stairs& s) {
  return flow({{"name", str(s.name)},
               {"start", vec(s.start_m)},
               {"yaw_deg", deg(s.yaw_rad)},
               {"steps", std::to_string(s.steps)},
               {"riser_m", num(s.riser_m)},
               {"tread_m", num(s.tread_m)},
               {"width_m", num(s.width_m)},
               {"landing_m", num(s.landing_m)}});
}

std::string object_entry(const MovableObject& o) {
  return flow({{"name", str(o.name)}, {"size_m", vec(o.size_m)}, {"mass_kg", num(o.mass_kg)}, {"center_m", vec(o.center_m)}});
}

std::string region_entry(const Region& g) {
  return flow({{"name", str(g.name)}, {"min", vec(g.min_m)}, {"max", vec(g.max_m)}});
}

// The outline the loader gives a ceiling without min and max (world_description.cpp).
std::pair<std::array<double, 2>, std::array<double, 2>> walls_outline(const WorldDescription& w) {
  std::array<double, 2> lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  std::array<double, 2> hi{-lo[0], -lo[1]};
  for (const auto& wall : w.walls)
    for (const auto& p : {wall.from_m, wall.to_m})
      for (std::size_t k = 0; k < 2; ++k) {
        lo[k] = std::min(lo[k], p[k] - wall.thickness_m / 2);
        hi[k] = std::max(hi[k], p[k] + wall.thickness_m / 2);
      }
  return {lo, hi};
}

template <typename T>
void write_list(Out& out, const char* key, const std::vector<T>& items,
                const std::function<std::string(const T&)>& entry, const std::function<std::string(const T&)>& name) {
  if (items.empty()) return;
  out.add(key, std::string(key) + ":");
  for (const auto& item : items) out.add("entry:" + name(item), "  - " + entry(item));
}

}  // namespace

bool ceiling_follows_walls(const WorldDescription& w) {
  if (!w.ceiling || w.walls.empty()) return false;
  const auto [lo, hi] = walls_outline(w);
  return lo == w.ceiling->min_m && hi == w.ceiling->max_m;
}

void fit_ceiling_to_walls(WorldDescription& w) {
  if (!w.ceiling || w.walls.empty()) return;
  std::tie(w.ceiling->min_m, w.ceiling->max_m) = walls_outline(w);
}

double degrees_as_written(double rad) { return std::strtod(deg(rad).c_str(), nullptr); }

WorldComments read_world_comments(const std::string& text) {
  WorldComments c;
  std::map<int, std::string> at;
  try {
    const YAML::Node root = YAML::Load(text);
    if (!root.IsMap()) return c;
    at = anchors(root);
  } catch (const std::exception&) {
    return c;
  }
  std::istringstream in(text);
  std::string line, block, last;
  for (int n = 0; std::getline(in, line); ++n) {
    line = clean(line);
    if (blank_or_comment(line)) {
      if (!block.empty() || !trailing_comment(line).empty() || line.find('#') != std::string::npos) block += line + "\n";
      continue;
    }
    const auto a = at.find(n);
    if (a != at.end()) {
      last = a->second;
      if (!block.empty()) c.above[last] += block;
      block.clear();
    } else if (!block.empty() && !last.empty()) {
      c.above[last] += block;  // inside an entry written over several lines: kept above it
      block.clear();
    }
    const std::string t = trailing_comment(line);
    if (!t.empty() && !last.empty()) c.trailing[last] += (c.trailing[last].empty() ? "" : " ") + t;
  }
  c.end = block;
  return c;
}

std::string write_world(const WorldDescription& w, const WorldComments& comments) {
  Out out(comments);
  out.add("world", "world: " + str(w.name));
  out.add("ground", "ground: " + flow({{"friction", num(w.ground_friction)}}));
  out.add("robot_start",
          "robot_start: " + flow({{"xy_m", vec(w.robot_start_m)}, {"yaw_deg", deg(w.robot_start_yaw_rad)}}));
  if (!w.robot_starts.empty()) {
    out.add("robot_starts", "robot_starts:");
    for (std::size_t i = 0; i < w.robot_starts.size(); ++i)
      out.add("robot_starts[" + std::to_string(i) + "]",
              "  - " + flow({{"xy_m", vec(w.robot_starts[i].xy_m)}, {"yaw_deg", deg(w.robot_starts[i].yaw_rad)}}));
  }
  write_list<BoxObstacle>(out, "boxes", w.boxes, [](const BoxObstacle& b) { return box_entry(b, nullptr); },
                          [](const BoxObstacle& b) { return b.name; });
  write_list<Prop>(out, "props", w.props, [](const Prop& p) { return box_entry(p.box, &p.kind); },
                   [](const Prop& p) { return p.box.name; });
  write_list<Wall>(out, "walls", w.walls, wall_entry, [](const Wall& x) { return x.name; });
  write_list<Door>(out, "doors", w.doors, door_entry, [](const Door& x) { return x.name; });
  write_list<Stairs>(out, "stairs", w.stairs, stairs_entry, [](const Stairs& x) { return x.name; });
  write_list<MovableObject>(out, "objects", w.objects, object_entry, [](const MovableObject& x) { return x.name; });
  write_list<Region>(out, "regions", w.regions, region_entry, [](const Region& x) { return x.name; });
  if (w.ceiling) {
    Fields f{{"height_m", num(w.ceiling->height_m)}, {"thickness_m", num(w.ceiling->thickness_m)}};
    if (!ceiling_follows_walls(w)) {
      f.emplace_back("min", vec(w.ceiling->min_m));
      f.emplace_back("max", vec(w.ceiling->max_m));
    }
    out.add("ceiling", "ceiling: " + flow(f));
  }
  return out.finish();
}

}  // namespace rise::sim
