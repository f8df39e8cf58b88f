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

namespace rise::semantic::testing {

/// The world turned by yaw_rad about the origin and moved by (dx, dy):
/// walls, doors, stairs, objects and a ceiling over the turned outline.
inline sim::WorldDescription turned(const sim::WorldDescription& w, double yaw_rad, double dx, double dy) {
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  const auto map = [&](const std::array<double, 2>& p) {
    return std::array<double, 2>{c * p[0] - s * p[1] + dx, s * p[0] + c * p[1] + dy};
  };
  sim::WorldDescription out = w;
  out.regions.clear();
  std::array<double, 2> lo{1e9, 1e9}, hi{-1e9, -1e9};
  for (auto& wall : out.walls) {
    wall.from_m = map(wall.from_m);
    wall.to_m = map(wall.to_m);
    for (const auto& p : {wall.from_m, wall.to_m})
      for (std::size_t k = 0; k < 2; ++k) {
        lo[k] = std::min(lo[k], p[k] - 0.5);
        hi[k] = std::max(hi[k], p[k] + 0.5);
      }
  }
  for (auto& d : out.doors) {
    d.hinge_m = map(d.hinge_m);
    d.yaw_rad += yaw_rad;
  }
  for (auto& st : out.stairs) {
    st.start_m = map(st.start_m);
    st.yaw_rad += yaw_rad;
  }
  for (auto& o : out.objects) {
    const auto xy = map({o.center_m[0], o.center_m[1]});
    o.center_m = {xy[0], xy[1], o.center_m[2]};
  }
  if (out.ceiling) {
    out.ceiling->min_m = lo;
    out.ceiling->max_m = hi;
  }
  return out;
}

/// building_poses() turned the same way.
inline std::vector<std::array<double, 3>> turned(const std::vector<std::array<double, 3>>& poses, double yaw_rad,
                                                 double dx, double dy) {
  std::vector<std::array<double, 3>> out;
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  for (const auto& p : poses) out.push_back({c * p[0] - s * p[1] + dx, s * p[0] + c * p[1] + dy, p[2] + yaw_rad});
  return out;
}

}  // namespace rise::semantic::testing
