#pragma once

// A robot's links, joints, inertia and collision shapes from its URDF
// (Debian's liburdfdom), mapped onto the simulator's robot model: a box
// chassis, four cylinder wheels (skid_steer) and the 3-joint arm with its
// one-finger gripper. The robot YAML names the URDF and the joints; what URDF
// has no words for (control mapping, motor limits, tracks, break limits,
// sensors) stays in the YAML.

#include <array>
#include <optional>
#include <string>
#include <utility>

#include "sim/robot_description.hpp"

namespace rise::sim {

/// The URDF joints the robot YAML names.
struct UrdfJointNames {
  /// Skid-steer wheels' continuous joints: front left, front right, rear left, rear right.
  std::optional<std::array<std::string, 4>> wheels;
  /// The arm's joints: shoulder yaw, shoulder pitch, elbow pitch (revolute), gripper (prismatic).
  std::optional<std::array<std::string, 4>> arm;
};

/// What read_urdf_robot takes from the URDF.
struct UrdfRobot {
  std::array<double, 3> chassis_size_m{};  ///< the root link's collision box
  double chassis_mass_kg = 0.0;
  /// Skid-steer only: radius, width, mass, wheelbase, track (the rest stays default).
  std::optional<WheelsDescription> wheels;
  /// Skid-steer only: ground to chassis bottom when the wheels stand on the ground.
  std::optional<double> clearance_m;
  std::optional<ArmDescription> arm;
  /// The arm's revolute limits (lower, upper) in rad, in the order of UrdfJointNames::arm.
  std::array<std::pair<double, double>, 3> arm_limits_rad{};
};

/// Reads `path`, parses it with urdf::parseURDF and maps it. The root link is the
/// chassis (base frame: chassis centre, x forward, y left, z up). Throws
/// std::runtime_error with liburdfdom's message (its log is captured, not
/// printed) or with what does not fit the simulator's model: a missing
/// joint, an unsupported shape (mesh, or a shape other than the body's), a
/// wrong joint type, axis or origin, an inertia that is not the solid
/// shape's (the simulator computes inertia from the shape and the URDF mass).
/// Not for the cyclic path.
UrdfRobot read_urdf_robot(const std::string& path, const UrdfJointNames& joints);
/// The same from the URDF's text (urdf::parseURDF; text that is not whole
/// UTF-8 is refused first); errors as read_urdf_robot's.
UrdfRobot parse_urdf_robot(const std::string& xml, const UrdfJointNames& joints);

}  // namespace rise::sim
