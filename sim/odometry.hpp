#pragma once

// Wheel or track odometry: the planar pose a robot computes by integrating
// its left and right ground speeds (track belt speed, wheel rim speed), with
// the errors of a real one (sensor_description.hpp: a per-side scale error
// and a random walk), so that it drifts.

#include <array>
#include <cstdint>
#include <random>

#include "sim/sensor_description.hpp"

namespace rise::sim {

/// Odometry's estimate in the world frame; it starts at the robot's true
/// start pose, so its difference from the true pose is its drift.
struct OdometryReading {
  std::array<double, 2> position_m{};
  double yaw_rad = 0.0;
  double linear_mps = 0.0;    ///< last step's estimate
  double angular_radps = 0.0;
  double distance_m = 0.0;    ///< path length travelled (estimate)
};

class Odometry {
 public:
  /// `gauge_m`: left to right contact distance (track gauge or wheel track).
  Odometry(const OdometryDescription& description, double gauge_m, std::array<double, 2> start_m,
           double start_yaw_rad, uint64_t seed);

  /// Integrates one step of the left and right ground speeds (m/s, + forward)
  /// over dt_s (differential drive, midpoint heading). Safe in the cyclic
  /// path: no allocation, never throws.
  void update(double left_mps, double right_mps, double dt_s);
  const OdometryReading& reading() const { return reading_; }

 private:
  OdometryDescription d_;
  double gauge_m_;
  std::array<double, 2> scale_{1.0, 1.0};
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  OdometryReading reading_;
};

}  // namespace rise::sim
