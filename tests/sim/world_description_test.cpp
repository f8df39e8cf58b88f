#include <catch2/catch.hpp>

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
  CHECK(w.doors.empty());
  CHECK(w.robot_start_m[0] == 0.0);
  CHECK_THROWS_WITH(load_world_description("/nonexistent/world.yaml"), Catch::Contains("/nonexistent/world.yaml:0"));
}
