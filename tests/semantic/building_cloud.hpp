#pragma once

// The example building (sim/worlds/building.yaml) as one registered cloud:
// the simulator's 3D laser scanner (the tracked robot's, 1 cm range noise)
// from a few known poses, each scan through its true pose into the world
// frame, merged. The poses see every room, both doors from both sides, the
// corridor and the staircase from below and from beyond its landing.

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

#include "semantic/cloud.hpp"
#include "semantic/segmentation.hpp"
#include "sim/laser_scanner.hpp"
#include "sim/simulation.hpp"
#include "sim/world_description.hpp"

namespace rise::semantic::testing {

inline const std::string kBuilding = std::string(RISE_SOURCE_DIR) + "/sim/worlds/building.yaml";
inline const std::string kTracked = std::string(RISE_SOURCE_DIR) + "/sim/robots/tracked_eod.yaml";

/// Every `keep`-th return of scans from `poses` (x, y, yaw rad) in `world`.
inline Cloud scan_world(const sim::WorldDescription& world, const std::vector<std::array<double, 3>>& poses,
                        int keep = 1) {
  Cloud cloud;
  const auto robot = sim::load_robot_description(kTracked);
  uint64_t seed = 11;
  for (const auto& pose : poses) {
    sim::WorldDescription w = world;
    w.robot_start_m = {pose[0], pose[1]};
    w.robot_start_yaw_rad = pose[2];
    sim::Simulation sim(robot, w);
    sim::LaserScanner scanner(*robot.sensors.laser, seed++);
    const sim::LaserScan scan = scanner.scan(sim);
    for (std::size_t i = 0; i < scan.points_world.size(); i += static_cast<std::size_t>(keep))
      cloud.points.push_back(scan.points_world[i]);
  }
  return cloud;
}

inline const std::vector<std::array<double, 3>>& building_poses() {
  static const std::vector<std::array<double, 3>> poses = {
      {0.0, 0.0, 0.0},     // room A, facing the closed door
      {-2.0, -1.5, 0.8},   // room A's south-west
      {6.0, -1.0, 3.1},    // room B, facing the door from behind
      {6.4, 2.0, 1.6},     // room B, below its doorway to the corridor
      {-2.5, 4.25, 0.0},   // corridor west, facing the stairs
      {-0.6, 4.25, 0.0},   // just before the first step
      {6.0, 4.25, 3.1},    // corridor east, beyond the landing
      {4.6, 4.25, 3.1},    // behind the landing
  };
  return poses;
}

/// The building's cloud, made once per test program.
inline const Cloud& building_cloud() {
  static const Cloud cloud = scan_world(sim::load_world_description(kBuilding), building_poses());
  return cloud;
}

/// Its segmentation with the default settings, made once.
inline const Segmentation& building_segmentation() {
  static const Segmentation seg = segment(building_cloud());
  return seg;
}

}  // namespace rise::semantic::testing
