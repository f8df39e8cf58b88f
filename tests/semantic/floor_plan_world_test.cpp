// `rise-semantic segment` on the real 2D maps of shared/data: the world it
// writes loads in the simulator, and the tracked robot, put 1 m in front of
// each doorway it fits (facing it, in free space), drives straight through
// to the other side.

#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "semantic/occupancy_grid.hpp"
#include "sim/simulation.hpp"
#include "sim/world_description.hpp"
#include "tests/semantic/building_cloud.hpp"
#include "tests/semantic/sim_drive.hpp"
#include "tests/test_data.hpp"

namespace fs = std::filesystem;
using namespace rise::semantic;
using namespace rise::semantic::testing;

namespace {

const std::string kProgram = std::string(RISE_BINARY_DIR) + "/bin/rise-semantic";
// The tracked robot's width over its tracks (0.52 m gauge + a 0.18 m track) and 5 cm each side.
constexpr double kFitsM = 0.52 + 0.18 + 0.1;

struct Map {
  const char* name;
  const char* source;  // relative to RISE_TEST_DATA
  const char* image;   // ROS maps: the image the yaml does not name
};

const Map kMaps[] = {
    {"pwr", "pointclouds/mdrwiega_3d_map_server/pwr_d20_f5_m4/pwr_d20_f5_m4.yaml",
     "pointclouds/mdrwiega_3d_map_server/pwr_d20_f5_m4/pwr_d20_f5_m4.pgm"},
    {"intel", "pointclouds/acschaefer_ple/intel-corrected.log.gz", ""},
    {"freiburg-101", "pointclouds/acschaefer_ple/freiburg-101-corrected.log.gz", ""},
    {"csail", "pointclouds/acschaefer_ple/csail-corrected.log.gz", ""},
    {"aces", "pointclouds/acschaefer_ple/aces-corrected.log.gz", ""},
};

// The tracked robot's footprint over its tracks, with 5 cm to spare all round.
constexpr double kRobotLengthM = 0.9 + 2 * 0.09 + 0.1, kRobotWidthM = 0.52 + 0.18 + 0.1;

bool free_at(const OccupancyGrid& g, const Eigen::Vector2d& p) {
  const Eigen::Vector2i c = g.cell_of(p);
  return g.contains(c.x(), c.y()) && g.at(c.x(), c.y()) == CellState::Free;
}

// Room for the robot with its base at `p` heading along unit `heading`: a
// free cell of the map, and its footprint clear of the world's walls.
bool room_at(const OccupancyGrid& g, const rise::sim::WorldDescription& w, const Eigen::Vector2d& p,
             const Eigen::Vector2d& heading) {
  if (!free_at(g, p)) return false;
  const Eigen::Vector2d side(-heading.y(), heading.x());
  for (const auto& wall : w.walls)
    for (const auto& b : rise::sim::wall_boxes(wall)) {
      if (b.center_m[2] - b.size_m[2] / 2 > 0.5) continue;  // a lintel
      const double c = std::cos(b.yaw_rad), s = std::sin(b.yaw_rad);
      for (double u = -kRobotLengthM / 2; u <= kRobotLengthM / 2; u += 0.05)
        for (double v = -kRobotWidthM / 2; v <= kRobotWidthM / 2; v += 0.05) {
          const Eigen::Vector2d d = p + u * heading + v * side - Eigen::Vector2d(b.center_m[0], b.center_m[1]);
          if (std::abs(c * d.x() + s * d.y()) < b.size_m[0] / 2 && std::abs(-s * d.x() + c * d.y()) < b.size_m[1] / 2)
            return false;
        }
    }
  return true;
}

}  // namespace

TEST_CASE("the tracked robot drives through every doorway it fits in the worlds rise-semantic segment makes of real maps",
          "[semantic]") {
  const fs::path dir = fs::temp_directory_path() / ("rise_floor_plan_world_test_" + std::to_string(getpid()));
  int driven = 0, cramped = 0;
  for (const Map& m : kMaps) {
    const std::string map = rise::test::data_file(m.source);
    if (map.empty()) {
      WARN("skipped " << m.name << ": " << m.source << " not in RISE_TEST_DATA");
      continue;
    }
    const std::string image = *m.image ? rise::test::data_file(m.image) : "";
    const fs::path out = dir / m.name;
    fs::remove_all(out);
    fs::create_directories(out);
    std::string cmd = kProgram + " segment " + map;
    if (!image.empty()) cmd += " --image " + image;
    cmd += " -o " + out.string() + " > " + (out / "stdout.txt").string() + " 2>&1";
    const int rc = std::system(cmd.c_str());
    INFO(m.name << ": " << cmd);
    REQUIRE(WIFEXITED(rc));
    REQUIRE(WEXITSTATUS(rc) == 0);
    const auto world = rise::sim::load_world_description((out / "world.yaml").string());
    CHECK(!world.walls.empty());
    const OccupancyGrid grid = image.empty() ? grid_from_scans(read_carmen_log(map)) : read_ros_map(map, image);
    for (const Doorway& d : doorways(world)) {
      if (d.width_m < kFitsM) continue;
      // From 1 m out on one side to 1.5 m beyond on the other, each with room for the robot.
      Eigen::Vector2d toward = d.normal;
      const auto clear = [&] {
        return room_at(grid, world, d.center - toward, toward) && room_at(grid, world, d.center + 1.5 * toward, toward);
      };
      if (!clear()) toward = -toward;
      if (!clear()) {
        WARN(m.name << ": doorway at (" << d.center.x() << ", " << d.center.y()
                    << ") has no room for the robot 1 m before and 1.5 m beyond it");
        ++cramped;
        continue;
      }
      const Eigen::Vector2d start = d.center - toward;
      auto w = world;
      w.robot_start_m = {start.x(), start.y()};
      w.robot_start_yaw_rad = std::atan2(toward.y(), toward.x());
      rise::sim::Simulation sim(rise::sim::load_robot_description(kTracked), w);
      sim.set_input(drive(1.0f, 1));
      std::vector<rise::sim::SimEvent> log;
      // Straight on for 2.5 m, or until 10 s have passed (stuck); where it crosses the wall line.
      Eigen::Vector2d p = start;
      double off_m = -1;
      for (double t = 0; t < 10.0 && (p - start).norm() < 2.5; t += 0.1) {
        run(sim, 0.1, log);
        p = {sim.snapshot().position_m[0], sim.snapshot().position_m[1]};
        if (off_m < 0 && toward.dot(p - d.center) >= 0) off_m = std::abs(d.along.dot(p - d.center));
      }
      const double past_m = toward.dot(p - d.center);
      std::string hit;
      for (const auto& e : log)
        if (e.kind == rise::sim::SimEventKind::CollisionStarted) hit += " " + e.a + "/" + e.b;
      INFO(m.name << ": doorway at (" << d.center.x() << ", " << d.center.y() << ") width " << d.width_m
                  << ": base " << past_m << " m past its wall line, crossed it " << off_m << " m off its middle, after "
                  << sim.time_s() << " s; collisions:" << hit);
      CHECK(past_m > 1.0);
      CHECK(off_m >= 0);
      CHECK(off_m < d.width_m / 2);
      CHECK_FALSE(any(log, rise::sim::SimEventKind::TippedOver));
      ++driven;
    }
  }
  fs::remove_all(dir);
  std::printf("drove through %d doorways; %d without room for the robot either side\n", driven, cramped);
}
