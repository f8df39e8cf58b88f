#pragma once

// What the simulator needs to know about a robot: its body, its running gear
// (wheels or tracks), an optional arm, and its control mapping — which panel
// controls drive which actuators. Loaded from YAML (sim/robots/*.yaml), whose
// `urdf` key may take the geometry from a URDF (sim/urdf_robot.hpp).

#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "sim/sensor_description.hpp"
#include "sim/sound_description.hpp"
#include "sim/urdf_tree.hpp"

namespace rise::sim {

/// skid_steer and tracked fit the simulator's fixed model (chassis, running
/// gear, optional 3-joint arm); urdf_tree is any URDF tree (sim/urdf_tree.hpp).
enum class RobotKind { SkidSteer, Tracked, UrdfTree };

struct ChassisDescription {
  std::array<double, 3> size_m{0.8, 0.5, 0.25};  ///< length (x), width (y), height (z)
  double mass_kg = 40.0;
  double clearance_m = 0.05;  ///< ground to chassis bottom at rest

  bool operator==(const ChassisDescription&) const = default;
};

struct WheelsDescription {
  double radius_m = 0.12;
  double width_m = 0.08;
  double mass_kg = 2.0;
  double friction = 1.0;          ///< Coulomb μ wheel/ground
  double wheelbase_m = 0.5;       ///< front to rear axle
  double track_m = 0.6;           ///< left to right wheel centre
  double max_torque_nm = 20.0;    ///< per wheel motor
  double max_speed_radps = 12.0;  ///< per wheel motor

  bool operator==(const WheelsDescription&) const = default;
};

/// Two rigid tracks whose ground contacts move at the track speed (contact
/// surface motion, Pecka et al. arXiv:1703.04316). Each track is a capsule
/// (the bottom run between the end rollers) plus a front run rising at
/// approach_rad so that the track can mount a step.
struct TracksDescription {
  double length_m = 0.8;           ///< end roller centre to end roller centre
  double radius_m = 0.08;          ///< end roller radius (half the track height)
  double gauge_m = 0.5;            ///< left to right track centre
  double approach_rad = 0.6;       ///< front run rise above the ground
  double approach_length_m = 0.3;  ///< front run, roller centre to roller centre
  double friction = 1.2;           ///< μ along the track
  double lateral_friction = 0.7;   ///< μ across the track
  double max_speed_mps = 1.0;

  bool operator==(const TracksDescription&) const = default;
};

/// A 3-joint arm (shoulder yaw, shoulder pitch, elbow pitch) and a one-finger
/// prismatic gripper on the chassis top. At zero joint angles the upper arm
/// rises at 45° forward and the forearm points straight ahead.
struct ArmDescription {
  std::array<double, 2> mount_m{0.15, 0.0};  ///< shoulder on the chassis top: x, y in the base frame
  double upper_length_m = 0.45;
  double forearm_length_m = 0.40;
  double link_mass_kg = 3.0;
  double link_width_m = 0.06;
  double gripper_stroke_m = 0.08;

  bool operator==(const ArmDescription&) const = default;
};

/// One axis of motion driven by a panel axis: command = value · max.
struct AxisMapping {
  std::string axis;
  double max = 0.0;  ///< m/s for linear, rad/s for angular and arm joints
  bool invert = false;

  bool operator==(const AxisMapping&) const = default;
};

/// A velocity-controlled arm joint: the panel axis sets the target rate.
struct ArmJointMapping {
  std::string joint;  ///< shoulder_yaw, shoulder_pitch or elbow_pitch
  AxisMapping axis;
  double min_rad = -M_PI;
  double max_rad = M_PI;
  double max_torque_nm = 50.0;     ///< motor
  double break_torque_nm = 500.0;  ///< constraint torque that breaks the joint (sustained 20 ms)

  bool operator==(const ArmJointMapping&) const = default;
};

struct ArmMapping {
  std::optional<std::pair<std::string, std::string>> enable;  ///< e.g. mode = arm
  std::vector<ArmJointMapping> joints;                        ///< in the order yaw, pitch, elbow
  std::string open_button;
  std::string close_button;
  double gripper_speed_mps = 0.05;
  double gripper_max_force_n = 80.0;

  bool operator==(const ArmMapping&) const = default;
};

enum class JointControlMode { Position, Velocity, Effort };

/// A urdf_tree robot's joint driven by the panel: the command is
/// axis value · max (+ mix), or ±max while its plus or minus button is held.
/// Position: target in rad or m, clamped to the joint's limits, reached at
/// up to the joint's velocity limit; velocity: rad/s or m/s (scaled by
/// speed_scale); effort: N·m or N. Motors hold (position, velocity) or go
/// slack (effort) while motion is not allowed.
struct JointControl {
  std::string joint;  ///< URDF joint name
  JointControlMode mode = JointControlMode::Velocity;
  AxisMapping axis;                                            ///< axis.axis empty: buttons only
  std::optional<AxisMapping> mix;                              ///< added, e.g. turn into a wheel's speed
  std::optional<std::pair<std::string, std::string>> buttons;  ///< plus, minus
  std::optional<std::pair<std::string, std::string>> enable;   ///< default: control.enable
  double max_effort = 0.0;  ///< motor limit, N·m or N: the URDF's effort unless given here
  double gain_per_s = 10.0;  ///< position: commanded rate = gain · error

  bool operator==(const JointControl&) const = default;
};

struct ControlMapping {
  AxisMapping linear;
  AxisMapping angular;
  /// Motion only while this switch is in this position (e.g. mode = drive).
  std::optional<std::pair<std::string, std::string>> enable;
  /// Speed scale by switch position (index = position).
  std::optional<std::pair<std::string, std::vector<double>>> speed_scale;
  /// Pressed → stop.
  std::optional<std::string> estop_button;
  /// Present iff the robot has an arm.
  std::optional<ArmMapping> arm;
  /// urdf_tree: the panel-driven joints, in file order.
  std::vector<JointControl> joints;

  bool operator==(const ControlMapping&) const = default;
};

struct RobotDescription {
  std::string name;
  std::string file;
  RobotKind kind = RobotKind::SkidSteer;
  ChassisDescription chassis;
  WheelsDescription wheels;  ///< skid_steer only
  TracksDescription tracks;  ///< tracked only
  std::optional<ArmDescription> arm;
  std::optional<UrdfTree> tree;  ///< urdf_tree only
  /// urdf_tree: Coulomb μ of a link's collision shapes (e.g. a caster's), by link name.
  std::vector<std::pair<std::string, double>> link_friction;
  ControlMapping control;
  SensorsDescription sensors;  ///< optional `sensors` section
  std::vector<SoundCueDescription> sounds;  ///< optional `sounds` section, in file order

  bool operator==(const RobotDescription&) const = default;
};

/// Loads a robot file (and the URDF it names, relative to it). Throws
/// std::runtime_error "file:line: key: message" for unknown keys, missing or
/// out-of-range values, and "file:line: urdf: <urdf>: reason" for a URDF that
/// liburdfdom refuses or that does not fit the simulator's model. Not for the
/// cyclic path.
RobotDescription load_robot_description(const std::string& path);
RobotDescription parse_robot_description(const std::string& text, const std::string& file);

}  // namespace rise::sim
