#include "sim/laser_scanner.hpp"

#include <cmath>
#include <limits>

#include "sim/simulation.hpp"

namespace rise::sim {

LaserScanner::LaserScanner(const LaserDescription& description, uint64_t seed) : d_(description), rng_(seed) {
  const int beams = d_.beams(), lines = d_.lines();
  directions_sensor_.reserve(static_cast<std::size_t>(beams) * static_cast<std::size_t>(lines));
  for (int k = 0; k < lines; ++k) {
    Eigen::Matrix3d R_sensor_line = Eigen::Matrix3d::Identity();
    if (d_.rotating)
      R_sensor_line = Eigen::AngleAxisd(d_.rotating->angle_rad(k), Eigen::Vector3d::Unit(d_.rotating->axis)).matrix();
    for (int i = 0; i < beams; ++i) {
      const double a = d_.beam_angle_rad(i);
      directions_sensor_.push_back(R_sensor_line * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0));
    }
  }
}

LaserScan LaserScanner::scan(const Simulation& sim, std::size_t robot) {
  LaserScan s;
  s.time_s = sim.time_s();
  s.T_world_sensor = sim.T_world_base(robot) * d_.mount.T_base_mount();
  s.beams = d_.beams();
  s.lines = d_.lines();
  s.ranges_m.assign(directions_sensor_.size(), std::numeric_limits<float>::quiet_NaN());
  s.points_sensor.reserve(directions_sensor_.size());
  s.points_world.reserve(directions_sensor_.size());
  const Eigen::Vector3d origin = s.T_world_sensor.translation();
  const Eigen::Matrix3d R = s.T_world_sensor.linear();
  // Sensor faults (sim_fault.hpp): drawn per ray from the fault's seed and
  // the scan's time, so a replayed scenario scans the same.
  std::vector<PhysicsFault> noise, dropout;
  for (auto& f : sim.faults(robot)) {
    if (f.kind == SimFaultKind::ScannerNoise) noise.push_back(f);
    if (f.kind == SimFaultKind::ScannerDropout) dropout.push_back(f);
  }
  const auto base = static_cast<uint64_t>(std::llround(s.time_s * 1000.0)) * directions_sensor_.size();
  for (std::size_t i = 0; i < directions_sensor_.size(); ++i) {
    const Eigen::Vector3d& dir = directions_sensor_[i];
    double r = sim.cast_ray_m(origin, R * dir, d_.max_range_m, robot);
    if (!std::isfinite(r)) continue;
    if (d_.noise_m > 0.0) r += d_.noise_m * normal_(rng_);
    bool lost = false;
    for (const auto& f : dropout) lost = lost || fault_uniform(f.seed, base + i) < (f.value > 0.0 ? f.value : 1.0);
    if (lost) continue;
    for (const auto& f : noise) r += (f.value > 0.0 ? f.value : 0.05) * fault_normal(f.seed, base + i);
    if (r < d_.min_range_m || r > d_.max_range_m) continue;
    s.ranges_m[i] = static_cast<float>(r);
    const Eigen::Vector3d p = r * dir;
    s.points_sensor.push_back(p.cast<float>());
    s.points_world.push_back((s.T_world_sensor * p).cast<float>());
  }
  return s;
}

void write_scan(const std::string& stem, const LaserScan& scan, PcdFormat format) {
  write_pcd(stem + ".pcd", scan.points_sensor, scan.T_world_sensor, format);
  write_pose(stem + ".pose", scan.T_world_sensor, scan.time_s);
}

}  // namespace rise::sim
