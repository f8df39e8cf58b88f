// The world YAML writer (the Environment Builder saves through it): load →
// write → load gives the same world, to the last bit, for every shipped world
// file and for the world rise-semantic writes from its scanned building; the
// comments of the file stay beside their entries, and go with a deleted one.

#include <catch2/catch.hpp>

#include <filesystem>

#include "panels/yaml_reader.hpp"
#include "semantic/world_export.hpp"
#include "sim/world_description.hpp"
#include "sim/world_writer.hpp"
#include "tests/semantic/building_cloud.hpp"

using namespace rise::sim;
namespace fs = std::filesystem;

namespace {

const std::string kSource = RISE_SOURCE_DIR;

template <typename A>
void same_array(const A& a, const A& b, const std::string& what) {
  INFO(what);
  for (std::size_t i = 0; i < a.size(); ++i) CHECK(a[i] == b[i]);
}

void same_box(const BoxObstacle& a, const BoxObstacle& b) {
  CHECK(a.name == b.name);
  same_array(a.center_m, b.center_m, a.name + ".center_m");
  same_array(a.size_m, b.size_m, a.name + ".size_m");
  CHECK(a.yaw_rad == b.yaw_rad);
}

void same_wall(const Wall& a, const Wall& b) {
  INFO("wall " << a.name);
  CHECK(a.name == b.name);
  same_array(a.from_m, b.from_m, "from");
  same_array(a.to_m, b.to_m, "to");
  CHECK(a.height_m == b.height_m);
  CHECK(a.thickness_m == b.thickness_m);
  REQUIRE(a.openings.size() == b.openings.size());
  for (std::size_t i = 0; i < a.openings.size(); ++i) {
    CHECK(a.openings[i].at_m == b.openings[i].at_m);
    CHECK(a.openings[i].width_m == b.openings[i].width_m);
    CHECK(a.openings[i].height_m == b.openings[i].height_m);
  }
}

void same_door(const Door& a, const Door& b) {
  INFO("door " << a.name);
  CHECK(a.name == b.name);
  same_array(a.hinge_m, b.hinge_m, "hinge");
  CHECK(a.width_m == b.width_m);
  CHECK(a.height_m == b.height_m);
  CHECK(a.thickness_m == b.thickness_m);
  CHECK(a.yaw_rad == b.yaw_rad);
  CHECK(a.open_max_rad == b.open_max_rad);
  CHECK(a.break_torque_nm == b.break_torque_nm);
  CHECK(a.break_time_ms == b.break_time_ms);
  CHECK(a.mass_kg == b.mass_kg);
  CHECK(a.friction_torque_nm == b.friction_torque_nm);
  CHECK(a.return_nm_per_rad == b.return_nm_per_rad);
}

void same_stairs(const Stairs& a, const Stairs& b) {
  INFO("stairs " << a.name);
  CHECK(a.name == b.name);
  same_array(a.start_m, b.start_m, "start");
  CHECK(a.yaw_rad == b.yaw_rad);
  CHECK(a.steps == b.steps);
  CHECK(a.riser_m == b.riser_m);
  CHECK(a.tread_m == b.tread_m);
  CHECK(a.width_m == b.width_m);
  CHECK(a.landing_m == b.landing_m);
}

// Everything the simulator builds from a world (not the file's name).
void check_same_world(const WorldDescription& a, const WorldDescription& b) {
  CHECK(a.name == b.name);
  CHECK(a.ground_friction == b.ground_friction);
  same_array(a.robot_start_m, b.robot_start_m, "robot_start");
  CHECK(a.robot_start_yaw_rad == b.robot_start_yaw_rad);
  REQUIRE(a.robot_starts.size() == b.robot_starts.size());
  for (std::size_t i = 0; i < a.robot_starts.size(); ++i) {
    same_array(a.robot_starts[i].xy_m, b.robot_starts[i].xy_m, "robot_starts");
    CHECK(a.robot_starts[i].yaw_rad == b.robot_starts[i].yaw_rad);
  }
  REQUIRE(a.ceiling.has_value() == b.ceiling.has_value());
  if (a.ceiling) {
    CHECK(a.ceiling->height_m == b.ceiling->height_m);
    CHECK(a.ceiling->thickness_m == b.ceiling->thickness_m);
    same_array(a.ceiling->min_m, b.ceiling->min_m, "ceiling.min");
    same_array(a.ceiling->max_m, b.ceiling->max_m, "ceiling.max");
  }
  REQUIRE(a.boxes.size() == b.boxes.size());
  for (std::size_t i = 0; i < a.boxes.size(); ++i) same_box(a.boxes[i], b.boxes[i]);
  REQUIRE(a.props.size() == b.props.size());
  for (std::size_t i = 0; i < a.props.size(); ++i) {
    same_box(a.props[i].box, b.props[i].box);
    CHECK(a.props[i].kind == b.props[i].kind);
  }
  REQUIRE(a.walls.size() == b.walls.size());
  for (std::size_t i = 0; i < a.walls.size(); ++i) same_wall(a.walls[i], b.walls[i]);
  REQUIRE(a.doors.size() == b.doors.size());
  for (std::size_t i = 0; i < a.doors.size(); ++i) same_door(a.doors[i], b.doors[i]);
  REQUIRE(a.stairs.size() == b.stairs.size());
  for (std::size_t i = 0; i < a.stairs.size(); ++i) same_stairs(a.stairs[i], b.stairs[i]);
  REQUIRE(a.objects.size() == b.objects.size());
  for (std::size_t i = 0; i < a.objects.size(); ++i) {
    CHECK(a.objects[i].name == b.objects[i].name);
    same_array(a.objects[i].size_m, b.objects[i].size_m, "object size");
    same_array(a.objects[i].center_m, b.objects[i].center_m, "object center");
    CHECK(a.objects[i].mass_kg == b.objects[i].mass_kg);
  }
  REQUIRE(a.regions.size() == b.regions.size());
  for (std::size_t i = 0; i < a.regions.size(); ++i) {
    CHECK(a.regions[i].name == b.regions[i].name);
    same_array(a.regions[i].min_m, b.regions[i].min_m, "region min");
    same_array(a.regions[i].max_m, b.regions[i].max_m, "region max");
  }
}

// Writes `text`'s world with its comments, loads that back; checks the
// meaning is the same and that writing again changes nothing.
std::string round_trip(const std::string& text, const std::string& file) {
  const WorldDescription original = parse_world_description(text, file);
  const std::string written = write_world(original, read_world_comments(text));
  INFO(written);
  const WorldDescription again = parse_world_description(written, file);
  check_same_world(original, again);
  CHECK(write_world(again, read_world_comments(written)) == written);
  return written;
}

std::vector<std::string> shipped_worlds() {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(kSource + "/sim/worlds"))
    if (e.path().extension() == ".yaml") out.push_back(e.path().string());
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

TEST_CASE("every shipped world reads back the same after writing, comments kept", "[sim][world_writer]") {
  const auto files = shipped_worlds();
  REQUIRE(files.size() >= 2);
  for (const auto& f : files) {
    INFO(f);
    const std::string text = rise::panels::read_text_file(f);
    const std::string written = round_trip(text, f);
    // Every comment line of the shipped file is in the written one.
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
      const auto hash = line.find('#');
      if (hash != std::string::npos) CHECK(written.find(line.substr(hash)) != std::string::npos);
    }
  }
}

TEST_CASE("the building's comments stay beside their entries", "[sim][world_writer]") {
  const std::string text = rise::panels::read_text_file(kSource + "/sim/worlds/building.yaml");
  const std::string written = round_trip(text, "building.yaml");
  CHECK(written.rfind("# A small building (see sim/README.md for the format).", 0) == 0);
  CHECK(written.find("  # Room A / corridor, with an open doorway at x -3..-1.5.\n"
                     "  - {name: wall_a_corridor_w, from: [-4, 3], to: [-3, 3], height: 2.5, thickness: 0.15}\n") !=
        std::string::npos);
  CHECK(written.find("# refer to the lines above by number).\nceiling: {height_m: 2.6, thickness_m: 0.1}\n") !=
        std::string::npos);
  CHECK(written.find("  - {name: door_ab, hinge: [3, -0.55], width: 1.1, height: 2, thickness: 0.04, yaw_deg: 90, "
                     "open_deg_max: 100, break_torque_nm: 900, mass_kg: 20}\n") != std::string::npos);
  CHECK(written.find("openings: [{at_m: 3, width_m: 0.9, height_m: 2}]}") != std::string::npos);

  // The entry under a comment deleted: its comment goes with it.
  WorldDescription w = parse_world_description(text, "building.yaml");
  w.walls.erase(w.walls.begin() + 4);  // wall_a_corridor_w
  const std::string without = write_world(w, read_world_comments(text));
  CHECK(without.find("Room A / corridor") == std::string::npos);
  CHECK(without.find("# Room A / room B, with the door's opening") != std::string::npos);
  CHECK_NOTHROW(parse_world_description(without, "building.yaml"));
}

TEST_CASE("line comments, quoted names, explicit ceilings and robot starts round trip", "[sim][world_writer]") {
  const std::string text =
      "world: \"my yard\"  # the name has a blank\n"
      "robot_start: {xy_m: [1.25, -2], yaw_deg: 33.3}\n"
      "robot_starts:\n"
      "  - {xy_m: [3, 1e-3], yaw_deg: -170}  # the second robot\n"
      "boxes:\n"
      "  - {name: \"true\", center_m: [0.1, 0.2, 0.3], size_m: [1, 1, 1], yaw_deg: 12.5}\n"
      "props:\n"
      "  - {name: shelf, kind: \"shelf #2\", center_m: [5, 5, 1], size_m: [0.4, 2, 2], yaw_deg: 45}\n"
      "doors:\n"
      "  # a door in the open\n"
      "  - {name: d, hinge: [0.3, 0.1], yaw_deg: 37, open_deg_max: 180, break_time_ms: 35, friction_torque_nm: 0,\n"
      "     return_nm_per_rad: 0.5}\n"
      "ceiling: {height_m: 3, min: [-1, -1], max: [2, 2]}\n"
      "# the end\n";
  const std::string written = round_trip(text, "t.yaml");
  CHECK(written.find("world: \"my yard\"  # the name has a blank\n") != std::string::npos);
  CHECK(written.find("  - {xy_m: [3, 0.001], yaw_deg: -170}  # the second robot\n") != std::string::npos);
  CHECK(written.find("  # a door in the open\n  - {name: d,") != std::string::npos);
  CHECK(written.find("ceiling: {height_m: 3, thickness_m: 0.1, min: [-1, -1], max: [2, 2]}\n# the end\n") !=
        std::string::npos);
}

TEST_CASE("a world rise-semantic writes from the scanned building reads back the same", "[sim][world_writer]") {
  rise::semantic::ExportSettings st;
  st.world_name = "building_found";
  const rise::semantic::SemanticNet net(rise::semantic::testing::building_segmentation());
  const std::string text = rise::semantic::world_yaml(net, st);
  const std::string written = round_trip(text, "building_found.yaml");
  CHECK(parse_world_description(written, "x.yaml").walls.size() >= 8);
}
