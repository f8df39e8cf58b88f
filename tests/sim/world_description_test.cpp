#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <fstream>
#include <sstream>

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

namespace {
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
}  // namespace

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

TEST_CASE("a wrong ceiling, opening or prop is refused with file:line and the key", "[sim]") {
  struct Case {
    const char* find;
    const char* replace;
    const char* expected;
  };
  const auto c = GENERATE(
      Case{"height_m: 2.4, ", "", "bad.yaml:2: ceiling.height_m: missing"},
      Case{"height_m: 2.4", "height_m: -2.4", "bad.yaml:2: ceiling.height_m: must be > 0"},
      Case{"thickness_m: 0.2", "thick_m: 0.2", "bad.yaml:2: ceiling.thick_m: unknown key"},
      Case{", max: [5, 2]", "", "bad.yaml:2: ceiling: give both min and max, or neither"},
      Case{"max: [5, 2]", "max: [5, -3]", "bad.yaml:2: ceiling.max: must exceed min on x and y"},
      Case{"at_m: 2.5, width_m: 1.0", "at_m: 3.5, width_m: 1.0",
           "bad.yaml:5: walls[0].openings[0]: outside the wall (3.5..4.5 m along a 4 m wall)"},
      Case{"at_m: 0.5, width_m: 0.9", "at_m: 2.0, width_m: 0.9",
           "bad.yaml:5: walls[0].openings[1]: overlaps openings[0]"},
      Case{"at_m: 0.5, ", "", "bad.yaml:5: walls[0].openings[1].at_m: missing"},
      Case{"at_m: 0.5", "at_m: -0.5", "bad.yaml:5: walls[0].openings[1].at_m: must be >= 0"},
      Case{"height_m: 2.5}", "height_m: 2.6}", "bad.yaml:5: walls[0].openings[1].height_m: must be <= the wall's height"},
      Case{"width_m: 1.0, height_m: 2.0", "width: 1.0, height_m: 2.0", "bad.yaml:5: walls[0].openings[0].width: unknown key"},
      Case{"kind: shelf, ", "", "bad.yaml:7: props[0].kind: missing"},
      Case{"name: shelf", "name: w", "bad.yaml:4: walls[0].name: duplicate name 'w'"},
      Case{"size_m: [1.0, 0.4, 1.8]", "size_m: [1.0, 0, 1.8]", "bad.yaml:7: props[0].size_m: must be > 0"},
      Case{", min: [-1, -2], max: [5, 2]", "", "no error"});
  std::string text = kNewKeys;
  const auto at = text.find(c.find);
  REQUIRE(at != std::string::npos);
  text.replace(at, std::string(c.find).size(), c.replace);
  const auto error = load_error(text);
  INFO(error);
  CHECK(error.rfind(c.expected, 0) == 0);
}

TEST_CASE("a ceiling without bounds in a world without walls is refused", "[sim]") {
  CHECK(load_error("ceiling: {height_m: 2.6}\n") == "bad.yaml:1: ceiling: needs min and max in a world without walls");
  CHECK(load_error("props: [{name: ceiling, kind: sign, center_m: [0, 0, 1], size_m: [1, 1, 1]}]\n"
                   "ceiling: {height_m: 2.6, min: [0, 0], max: [1, 1]}\n") ==
        "bad.yaml:2: ceiling: another entity is named 'ceiling'");
}

TEST_CASE("a broken world file is refused with file:line and the key", "[sim]") {
  struct Case {
    const char* find;
    const char* replace;
    const char* expected;
  };
  const auto c = GENERATE(
      Case{"open_deg_max: 100", "open_max: 100", "bad.yaml:24: doors[0].open_max: unknown key"},
      Case{"riser_m: 0.17", "riser_m: -0.17", "bad.yaml:26: stairs[0].riser_m: must be > 0"},
      Case{"steps: 6", "steps: six", "bad.yaml:26: stairs[0].steps: cannot read 'six'"},
      Case{"max: [8.5, -1.0, 1.5]", "max: [8.5, -3.0, 1.5]", "bad.yaml:31: regions[0].max: must exceed min"},
      Case{"hinge: [3.0, -0.55]", "hinge: [3.0]", "bad.yaml:23: doors[0].hinge: expected [x, y]"},
      Case{"to: [9, -3]", "to: [-4, -3]", "bad.yaml:11: walls[0].to: must differ from 'from'"},
      Case{"name: wall_east", "name: wall_west", "bad.yaml:13: walls[2].name: duplicate name 'wall_west'"},
      Case{"mass_kg: 4.0, ", "", "bad.yaml:29: objects[0].mass_kg: missing"},
      Case{"regions:", "zones:", "bad.yaml:30: zones: unknown key"});
  std::string text = building_text();
  const auto at = text.find(c.find);
  REQUIRE(at != std::string::npos);
  text.replace(at, std::string(c.find).size(), c.replace);
  const auto error = load_error(text);
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
  CHECK_THROWS_WITH(load_world_description("/nonexistent/world.yaml"), Catch::Contains("/nonexistent/world.yaml:0"));
}
