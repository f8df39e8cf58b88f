#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "sim/world_description.hpp"

using namespace rise::sim;

namespace {
const std::string kBuilding = std::string(RISE_SOURCE_DIR) + "/sim/worlds/building.yaml";

std::string building_text() {
  std::ifstream in(kBuilding);
  std::stringstream buf;
  buf << in.rdbuf();
  return buf.str();
}

std::string load_error(const std::string& text) {
  try {
    parse_world_description(text, "bad.yaml");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

// A world with every new key: a ceiling with explicit bounds, a wall with two
// openings (listed out of order), a prop.
const char* const kNewKeys = R"(world: rooms
ceiling: {height_m: 2.4, thickness_m: 0.2, min: [-1, -2], max: [5, 2]}
walls:
  - {name: w, from: [0, 0], to: [4, 0], height: 2.5, thickness: 0.2,
     openings: [{at_m: 2.5, width_m: 1.0, height_m: 2.0}, {at_m: 0.5, width_m: 0.9, height_m: 2.5}]}
props:
  - {name: shelf, kind: shelf, center_m: [1, 1, 0.9], size_m: [1.0, 0.4, 1.8], yaw_deg: 90}
)";

// A broken world file: in `world`, the first `find` replaced by `replace`
// is refused with a message that starts with `expected`.
enum class World { Building, NewKeys };
struct Edit {
  World world;
  std::string find;
  std::string replace;
  std::string expected;
};

// The rows of tests/sim/data/broken_worlds.txt ("world | find | replace |
// expected", "-" for an empty field).
std::vector<Edit> broken_world_edits() {
  std::ifstream in(std::string(RISE_SOURCE_DIR) + "/tests/sim/data/broken_worlds.txt");
  std::vector<Edit> out;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> f;
    for (std::size_t at = 0;;) {
      const auto bar = line.find(" | ", at);
      f.push_back(line.substr(at, bar == std::string::npos ? std::string::npos : bar - at));
      if (bar == std::string::npos) break;
      at = bar + 3;
    }
    for (auto& x : f)
      if (x == "-") x.clear();
    if (f.size() == 4) out.push_back({f[0] == "building" ? World::Building : World::NewKeys, f[1], f[2], f[3]});
    else out.push_back({World::NewKeys, "", "", "malformed row: " + line});  // fails below
  }
  if (out.empty()) out.push_back({World::NewKeys, "", "", "no rows in broken_worlds.txt"});
  return out;
}

// The load error after the edit ("no error" when it loads).
std::string error_after(const Edit& edit) {
  std::string text = edit.world == World::Building ? building_text() : std::string(kNewKeys);
  const auto at = text.find(edit.find);
  if (edit.find.empty() || at == std::string::npos) return "'" + edit.find + "' is not in the file";
  text.replace(at, edit.find.size(), edit.replace);
  return load_error(text);
}
}  // namespace

TEST_CASE("the shipped building world loads with its door, staircase, object and region", "[sim]") {
  const auto w = load_world_description(kBuilding);
  CHECK(w.name == "building");
  CHECK(w.walls.size() == 9);
  REQUIRE(w.doors.size() == 1);
  CHECK(w.doors[0].name == "door_ab");
  CHECK(w.doors[0].width_m == Approx(1.1).margin(1e-9));
  CHECK(w.doors[0].yaw_rad == Approx(M_PI / 2).margin(1e-9));
  CHECK(w.doors[0].open_max_rad == Approx(100.0 * M_PI / 180.0).margin(1e-9));
  CHECK(w.doors[0].break_torque_nm == Approx(900.0).margin(1e-9));
  REQUIRE(w.stairs.size() == 1);
  const auto& s = w.stairs[0];
  CHECK(s.steps == 6);
  CHECK(s.riser_m == Approx(0.17).margin(1e-9));
  CHECK(s.tread_m == Approx(0.28).margin(1e-9));
  // "30°-ish": a 17/28 stair climbs at 31.3°.
  CHECK(std::atan2(s.riser_m, s.tread_m) * 180.0 / M_PI == Approx(31.3).margin(0.1));
  CHECK(s.landing_height_m() == Approx(1.02).margin(1e-9));
  REQUIRE(w.objects.size() == 1);
  CHECK(w.objects[0].name == "hazardous_object");
  CHECK(w.objects[0].mass_kg == Approx(4.0).margin(1e-9));
  REQUIRE(w.regions.size() == 1);
  CHECK(w.regions[0].name == "neutralization_area");
  CHECK(w.regions[0].max_m[0] == Approx(8.5).margin(1e-9));
  // The ceiling over the walls' outline (end points ± half the 0.15 m thickness).
  REQUIRE(w.ceiling.has_value());
  CHECK(w.ceiling->height_m == Approx(2.6).margin(1e-9));
  CHECK(w.ceiling->min_m[0] == Approx(-4.075).margin(1e-9));
  CHECK(w.ceiling->max_m[1] == Approx(5.575).margin(1e-9));
  CHECK(w.walls[6].name == "wall_b_corridor");
  REQUIRE(w.walls[6].openings.size() == 1);
  CHECK(w.walls[6].openings[0].at_m == Approx(3.0).margin(1e-9));
}


TEST_CASE("the ceiling, a wall's openings and a prop parse from the world file", "[sim]") {
  const auto w = parse_world_description(kNewKeys, "rooms.yaml");
  REQUIRE(w.ceiling.has_value());
  CHECK(w.ceiling->height_m == Approx(2.4).margin(1e-9));
  CHECK(w.ceiling->thickness_m == Approx(0.2).margin(1e-9));
  CHECK(w.ceiling->min_m == std::array<double, 2>{-1, -2});
  CHECK(w.ceiling->max_m == std::array<double, 2>{5, 2});
  const auto slab = ceiling_box(*w.ceiling);
  CHECK(slab.name == "ceiling");
  CHECK(slab.center_m[2] - slab.size_m[2] / 2 == Approx(2.4).margin(1e-9));  // underside at height_m
  CHECK(slab.size_m[0] == Approx(6.0).margin(1e-9));
  REQUIRE(w.walls.size() == 1);
  REQUIRE(w.walls[0].openings.size() == 2);
  CHECK(w.walls[0].openings[0].at_m == Approx(0.5).margin(1e-9));  // sorted along the wall
  CHECK(w.walls[0].openings[1].width_m == Approx(1.0).margin(1e-9));
  REQUIRE(w.props.size() == 1);
  CHECK(w.props[0].box.name == "shelf");
  CHECK(w.props[0].kind == "shelf");
  CHECK(w.props[0].box.yaw_rad == Approx(M_PI / 2).margin(1e-9));
  CHECK(w.props[0].box.size_m[2] == Approx(1.8).margin(1e-9));
}

TEST_CASE("a wall with openings is built of the pieces beside them and the lintels above", "[sim]") {
  const auto w = parse_world_description(kNewKeys, "rooms.yaml");
  // Along x from -0.1 (half the thickness before `from`) to 4.1: a piece
  // -0.1..0.5, the full-height opening 0.5..1.4 (no lintel), a piece 1.4..2.5,
  // the opening 2.5..3.5 with a lintel 2.0..2.5 m high, a piece 3.5..4.1.
  const auto boxes = wall_boxes(w.walls[0]);
  REQUIRE(boxes.size() == 4);
  struct Expected {
    double x0, x1, z0, z1;
  };
  const Expected expected[] = {{-0.1, 0.5, 0.0, 2.5}, {1.4, 2.5, 0.0, 2.5}, {2.5, 3.5, 2.0, 2.5}, {3.5, 4.1, 0.0, 2.5}};
  for (std::size_t i = 0; i < 4; ++i) {
    INFO("piece " << i);
    const auto& b = boxes[i];
    CHECK(b.name == "w");
    CHECK(b.center_m[0] - b.size_m[0] / 2 == Approx(expected[i].x0).margin(1e-9));
    CHECK(b.center_m[0] + b.size_m[0] / 2 == Approx(expected[i].x1).margin(1e-9));
    CHECK(b.center_m[1] == Approx(0.0).margin(1e-9));
    CHECK(b.size_m[1] == Approx(0.2).margin(1e-9));
    CHECK(b.center_m[2] - b.size_m[2] / 2 == Approx(expected[i].z0).margin(1e-9));
    CHECK(b.center_m[2] + b.size_m[2] / 2 == Approx(expected[i].z1).margin(1e-9));
  }
  // Without openings: one box, lengthened by the thickness.
  auto plain = w.walls[0];
  plain.openings.clear();
  const auto one = wall_boxes(plain);
  REQUIRE(one.size() == 1);
  CHECK(one[0].size_m[0] == Approx(4.2).margin(1e-9));
  CHECK(one[0].center_m[0] == Approx(2.0).margin(1e-9));
}

TEST_CASE("a ceiling without bounds in a world without walls is refused", "[sim]") {
  CHECK(load_error("ceiling: {height_m: 2.6}\n") == "bad.yaml:1: ceiling: needs min and max in a world without walls");
  CHECK(load_error("props: [{name: ceiling, kind: sign, center_m: [0, 0, 1], size_m: [1, 1, 1]}]\n"
                   "ceiling: {height_m: 2.6, min: [0, 0], max: [1, 1]}\n") ==
        "bad.yaml:2: ceiling: another entity is named 'ceiling'");
}

TEST_CASE("a broken world file, old keys or new, is refused with file:line and the key", "[sim]") {
  const auto c = GENERATE(from_range(broken_world_edits()));
  const auto error = error_after(c);
  INFO(error);
  CHECK(error.rfind(c.expected, 0) == 0);
}

TEST_CASE("a world file without the new sections is still a valid world", "[sim]") {
  const auto w = parse_world_description("world: empty\n", "w.yaml");
  CHECK(w.walls.empty());
  CHECK_FALSE(w.ceiling.has_value());
  CHECK(w.props.empty());
  CHECK(w.doors.empty());
  CHECK(w.robot_start_m[0] == 0.0);
  CHECK_THROWS_WITH(load_world_description("/nonexistent/world.yaml"), Catch::Contains("/nonexistent/world.yaml: cannot open: No such file or directory"));
}
