#pragma once

// A sequence of scans of the example building (sim/worlds/building.yaml)
// with their true poses, and odometry that drifts away from them: the input
// of the SLAM tests and of the `rise-semantic map` integration test.

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "semantic/cloud.hpp"
#include "sim/laser_scanner.hpp"
#include "sim/simulation.hpp"
#include "tests/semantic/building_cloud.hpp"

namespace rise::semantic::testing {

/// yaw about z, then pitch about y, then roll about x, at (x, y, z).
inline Eigen::Isometry3d pose(double x, double y, double z, double yaw_rad, double pitch_rad = 0.0,
                              double roll_rad = 0.0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

inline double translation_error_m(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm();
}

inline double rotation_error_rad(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
}

/// Odometry that drifts: each true step of the base turned by an extra 2°
/// of yaw and stretched 3 %, chained from the true first pose; of the
/// sensor, `T_base_sensor` on the base.
inline std::vector<Eigen::Isometry3d> drifting_odometry(
    const std::vector<Eigen::Isometry3d>& truth, const Eigen::Isometry3d& T_base_sensor = Eigen::Isometry3d::Identity()) {
  const Eigen::Isometry3d T_sensor_base = T_base_sensor.inverse();
  std::vector<Eigen::Isometry3d> odometry{truth[0] * T_sensor_base};  // of the base
  for (std::size_t i = 1; i < truth.size(); ++i) {
    Eigen::Isometry3d step = (truth[i - 1] * T_sensor_base).inverse() * (truth[i] * T_sensor_base);
    step.translation() *= 1.03;
    odometry.push_back(odometry.back() * step * pose(0, 0, 0, 2.0 * M_PI / 180.0));
  }
  for (auto& T : odometry) T = T * T_base_sensor;
  return odometry;
}

struct LaserScans {
  std::vector<Cloud> clouds;                      ///< sensor frame
  std::vector<Eigen::Isometry3d> T_world_sensor;  ///< the truth
  Eigen::Isometry3d T_base_sensor = Eigen::Isometry3d::Identity();
};

/// The robot file's own laser (a SICK-like line scanner turned about its y
/// axis, σ 1 cm), coarsened to `resolution_rad` beams × `lines` (2° × 60:
/// 5 460 rays), scanning from the robot standing at each (x, y, yaw) stop in
/// the building: the simulator builds the robot there, as it stands before
/// its first step.
inline LaserScans laser_scans(const std::vector<Eigen::Vector3d>& stops_xy_yaw, uint64_t seed,
                              double resolution_rad = 2.0 * M_PI / 180.0, int lines = 60) {
  const auto robot = sim::load_robot_description(kTracked);
  if (!robot.sensors.laser || !robot.sensors.laser->rotating)
    throw std::runtime_error(kTracked + ": no rotating laser");
  sim::LaserDescription laser = *robot.sensors.laser;
  laser.resolution_rad = resolution_rad;
  laser.rotating->steps = lines;
  sim::LaserScanner scanner(laser, seed);
  LaserScans out;
  for (const auto& stop : stops_xy_yaw) {
    auto world = sim::load_world_description(kBuilding);
    world.robot_start_m = {stop.x(), stop.y()};
    world.robot_start_yaw_rad = stop.z();
    sim::Simulation sim(robot, world);
    const sim::LaserScan scan = scanner.scan(sim);
    Cloud c;
    c.points = scan.points_sensor;
    out.clouds.push_back(std::move(c));
    out.T_world_sensor.push_back(scan.T_world_sensor);
    out.T_base_sensor = sim.T_world_base().inverse() * scan.T_world_sensor;
  }
  return out;
}

struct Errors {
  double max_t_m = 0, max_r_rad = 0, sum_t_m = 0;
};

inline Errors errors(const std::vector<Eigen::Isometry3d>& got, const std::vector<Eigen::Isometry3d>& truth) {
  Errors e;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    e.max_t_m = std::max(e.max_t_m, translation_error_m(got[i], truth[i]));
    e.max_r_rad = std::max(e.max_r_rad, rotation_error_rad(got[i], truth[i]));
    e.sum_t_m += translation_error_m(got[i], truth[i]);
  }
  return e;
}

}  // namespace rise::semantic::testing
