#pragma once

// An IMU on the chassis: angular rate and specific force (what an
// accelerometer measures: acceleration minus gravity, so at rest it reads
// +9.81 m/s² up) in the base frame, with bias and white noise
// (sensor_description.hpp).

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <random>

#include "sim/sensor_description.hpp"

namespace rise::sim {

struct ImuReading {
  std::array<double, 3> angular_velocity_radps{};    ///< base frame
  std::array<double, 3> linear_acceleration_mps2{};  ///< specific force, base frame
};

class Imu {
 public:
  Imu(const ImuDescription& description, const Eigen::Vector3d& gravity_world_mps2, uint64_t seed);

  /// One sample from the body's state after a step: its rotation, its
  /// world-frame velocity (differenced against the previous sample's over
  /// dt_s; the first sample sees no acceleration) and its angular velocity
  /// in the body frame. Safe in the cyclic path: no allocation, never throws.
  void update(const Eigen::Matrix3d& R_world_base, const Eigen::Vector3d& velocity_world_mps,
              const Eigen::Vector3d& angular_velocity_base_radps, double dt_s);
  const ImuReading& reading() const { return reading_; }
  /// The biases drawn at construction (gyro rad/s, accelerometer m/s²).
  const std::array<double, 3>& gyro_bias_radps() const { return gyro_bias_; }
  const std::array<double, 3>& accel_bias_mps2() const { return accel_bias_; }

 private:
  ImuDescription d_;
  Eigen::Vector3d gravity_world_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::array<double, 3> gyro_bias_{};
  std::array<double, 3> accel_bias_{};
  Eigen::Vector3d last_velocity_world_ = Eigen::Vector3d::Zero();
  bool first_ = true;
  ImuReading reading_;
};

}  // namespace rise::sim
