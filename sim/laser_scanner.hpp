#pragma once

// A laser scanner on the robot, by ray casting the simulated world: a 2D
// line scanner, or in 3D mode a rotating 2D scanner — the scan plane turned
// about an axis in steps, as the paper's 3DLSN unit turns a SICK LMS200
// (sensor_description.hpp). Ranges get Gaussian noise from a seeded RNG:
// the same seed, world and pose give the same scan, bit for bit.

#include <Eigen/Geometry>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "sim/pcd_file.hpp"
#include "sim/sensor_description.hpp"

namespace rise::sim {

class Simulation;

/// One scan. The scan is taken at one instant (stop-and-go scanning, as the
/// paper's robot stands still while its 3DLSN turns).
struct LaserScan {
  double time_s = 0.0;
  Eigen::Isometry3d T_world_sensor = Eigen::Isometry3d::Identity();  ///< the true sensor pose
  int beams = 0;  ///< per line
  int lines = 0;  ///< 1 for a 2D scan, rotation steps for 3D
  /// lines × beams, line-major: the measured range of every ray (m), NaN
  /// where there was no return within min..max range.
  std::vector<float> ranges_m;
  std::vector<Eigen::Vector3f> points_sensor;  ///< the returns, sensor frame
  std::vector<Eigen::Vector3f> points_world;   ///< the same returns through the true T_world_sensor
};

class LaserScanner {
 public:
  LaserScanner(const LaserDescription& description, uint64_t seed);

  /// Scans from robot `robot`'s current true pose (the other robots are in
  /// the scan, its own parts are not). Allocates (not for the
  /// cyclic path); never throws.
  LaserScan scan(const Simulation& sim, std::size_t robot = 0);
  /// Unit ray directions in the sensor frame, lines × beams, line-major.
  const std::vector<Eigen::Vector3d>& directions_sensor() const { return directions_sensor_; }
  const LaserDescription& description() const { return d_; }

 private:
  LaserDescription d_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::vector<Eigen::Vector3d> directions_sensor_;
};

/// Writes `<stem>.pcd` (points in the sensor frame, VIEWPOINT = the true
/// T_world_sensor) and `<stem>.pose` beside it (sim/README.md). Throws
/// std::runtime_error "path: cannot write: <strerror>" when a file cannot be written.
void write_scan(const std::string& stem, const LaserScan& scan, PcdFormat format);

}  // namespace rise::sim
