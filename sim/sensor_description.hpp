#pragma once

// What the robot carries to sense the world (the robot file's `sensors`
// section, sim/README.md): a laser scanner — a 2D line scanner, or a 2D
// scanner whose scan plane turns about an axis in steps, giving 3D scans as
// the paper's 3DLSN unit (a rotated SICK LMS200) does — wheel/track
// odometry, an IMU on the chassis and named camera mounts for viewers.

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace rise::sim {

/// Where a sensor sits on the chassis: position in the base frame (the
/// chassis centre; x forward, y left, z up) and roll, pitch, yaw about the
/// base's fixed x, y, z axes (R = Rz(yaw)·Ry(pitch)·Rx(roll), as URDF's rpy).
struct Mount {
  std::array<double, 3> position_m{};
  std::array<double, 3> rpy_rad{};

  Eigen::Isometry3d T_base_mount() const {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translate(Eigen::Vector3d(position_m[0], position_m[1], position_m[2]));
    T.rotate(Eigen::AngleAxisd(rpy_rad[2], Eigen::Vector3d::UnitZ()) *
             Eigen::AngleAxisd(rpy_rad[1], Eigen::Vector3d::UnitY()) *
             Eigen::AngleAxisd(rpy_rad[0], Eigen::Vector3d::UnitX()));
    return T;
  }

  bool operator==(const Mount&) const = default;
};

/// The 3D mode: the scan plane (the sensor's x–y plane) turned about one of
/// the sensor's axes through its origin, `steps` lines over `sweep_rad`.
struct LaserRotation {
  int axis = 2;  ///< 0 = x, 1 = y, 2 = z of the sensor frame
  int steps = 90;
  double sweep_rad = 2 * M_PI;  ///< a full turn has no duplicate line; less includes both ends

  /// Angle of line k (rad).
  double angle_rad(int k) const {
    if (sweep_rad >= 2 * M_PI - 1e-9) return sweep_rad * k / steps;
    return steps == 1 ? 0.0 : -sweep_rad / 2 + sweep_rad * k / (steps - 1);
  }

  bool operator==(const LaserRotation&) const = default;
};

/// A time-of-flight line scanner: beams in the sensor's x–y plane from
/// −fov/2 to +fov/2 about its z axis (beam 0 towards −y), ranges
/// min..max with Gaussian range noise σ = noise_m.
struct LaserDescription {
  Mount mount;
  double fov_rad = M_PI;
  double resolution_rad = 0.5 * M_PI / 180.0;
  double min_range_m = 0.1;
  double max_range_m = 30.0;
  double noise_m = 0.0;
  std::optional<LaserRotation> rotating;

  /// Beams per line: a full circle has no duplicate beam.
  int beams() const {
    if (fov_rad >= 2 * M_PI - 1e-9) return static_cast<int>(std::lround(2 * M_PI / resolution_rad));
    return static_cast<int>(std::floor(fov_rad / resolution_rad + 1e-9)) + 1;
  }
  int lines() const { return rotating ? rotating->steps : 1; }
  /// Angle of beam i in the scan plane (rad).
  double beam_angle_rad(int i) const { return -fov_rad / 2 + resolution_rad * i; }

  bool operator==(const LaserDescription&) const = default;
};

/// Track or wheel odometry: each side's travel is scaled by (1 + e_side),
/// e_side ~ N(0, scale_sigma) drawn once (a systematic error: the robot
/// believes it curves), plus white noise of σ = noise_per_sqrt_m·√(travel)
/// per step (a random walk, growing with the square root of the distance).
struct OdometryDescription {
  double scale_sigma = 0.0;
  double noise_per_sqrt_m = 0.0;

  bool operator==(const OdometryDescription&) const = default;
};

/// An IMU at the chassis centre, axes of the base frame. Each axis has a
/// constant bias ~ N(0, bias σ) drawn once plus white noise per sample.
struct ImuDescription {
  double gyro_noise_radps = 0.0;
  double gyro_bias_radps = 0.0;
  double accel_noise_mps2 = 0.0;
  double accel_bias_mps2 = 0.0;

  bool operator==(const ImuDescription&) const = default;
};

/// A camera for viewers (x forward, y left, z up; the image looks along x).
struct CameraMount {
  std::string name;
  Mount mount;

  bool operator==(const CameraMount&) const = default;
};

struct SensorsDescription {
  uint64_t seed = 1;  ///< all sensor noise comes from RNGs seeded with this
  std::optional<LaserDescription> laser;
  OdometryDescription odometry;
  ImuDescription imu;
  std::vector<CameraMount> cameras;

  bool operator==(const SensorsDescription&) const = default;
};

}  // namespace rise::sim
