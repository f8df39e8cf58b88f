#pragma once

// The ODE world with one robot (skid-steer or tracked, optionally with an
// arm), stepped at a fixed 1 ms. Pure simulation: no clock, no I/O. The same
// inputs give the same trajectory, bit for bit. Each step also records the
// semantic events a scenario engine scores (collisions, doors, regions,
// stairs, broken joints, tip-over).

#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sim/imu.hpp"
#include "sim/odometry.hpp"
#include "sim/robot_description.hpp"
#include "sim/world_description.hpp"

namespace rise::sim {

/// The panel as the robot's control mapping reads it (filled by the LCM
/// adapter from PanelState).
struct ControlInput {
  std::map<std::string, float> axes;       ///< -1..1
  std::map<std::string, bool> buttons;
  std::map<std::string, int> switches;     ///< position index
  std::map<std::string, std::string> switch_labels;
  bool failsafe = true;  ///< panel says its controls cannot be trusted
  bool deadman = false;
  bool fresh = false;    ///< a panel state arrived within the sim's panel timeout
};

struct WheelState {
  std::string name;
  double position_rad = 0.0;
  double velocity_radps = 0.0;
  double effort_nm = 0.0;  ///< motor torque applied in the last step
};

/// An arm joint (rad, rad/s, N·m) or the gripper (m, m/s, N).
struct JointState {
  std::string name;
  double position = 0.0;
  double velocity = 0.0;
  double effort = 0.0;  ///< motor + limit torque/force along the axis in the last step
  bool broken = false;  ///< destroyed by an overload (position etc. then read 0)
};

enum class SimEventKind {
  CollisionStarted,  ///< a = robot part, b = entity
  CollisionStopped,  ///< a = robot part, b = entity (no contact for 50 ms)
  DoorOpened,        ///< a = door; |angle| > 10°
  DoorClosed,        ///< a = door; |angle| < 5° again
  JointBroken,       ///< a = robot or door, b = joint; detail = load
  RegionEntered,     ///< a = robot, b = region; base inside the box
  RegionLeft,        ///< a = robot, b = region
  ObjectMoved,       ///< a = object; > 5 cm from its start (once)
  StairsClimbed,     ///< a = robot, b = stairs; base above the landing, on it
  TippedOver,        ///< a = robot; base z axis > 60° from vertical
  CollisionContinues,  ///< a = robot part, b = entity; each full second a collision lasts, detail "N s"
};
/// Stable snake_case name, e.g. "door_opened" (also the LCM `kind`).
const char* to_string(SimEventKind kind);

/// Something that happened in the world during a step.
struct SimEvent {
  double time_s = 0.0;  ///< sim time at the end of the step
  SimEventKind kind = SimEventKind::CollisionStarted;
  std::string a;
  std::string b;
  std::string detail;
};

struct RobotSnapshot {
  double time_s = 0.0;
  std::array<double, 3> position_m{};
  std::array<double, 4> orientation_wxyz{1, 0, 0, 0};
  std::array<double, 3> linear_velocity_mps{};     ///< base frame
  std::array<double, 3> angular_velocity_radps{};  ///< base frame
  std::vector<WheelState> wheels;                  ///< fl, fr, rl, rr; tracked: track_left/right rollers
  std::vector<JointState> joints;                  ///< arm: shoulder_yaw, shoulder_pitch, elbow_pitch, gripper
  std::vector<std::string> contacts;               ///< entities touched (not the ground)
  std::array<double, 3> gripper_position_m{};      ///< finger centre in the world (arm robots)
  double damage = 0.0;                             ///< 0 intact .. 1 destroyed (broken joints)
  bool arm_enabled = false;
  bool motors_enabled = false;
  std::string stop_reason;
  double commanded_linear_mps = 0.0;
  double commanded_angular_radps = 0.0;
  OdometryReading odometry;  ///< from the tracks' belt speeds or the wheels' rates, with the robot file's noise
  ImuReading imu;            ///< the last step's sample

  double yaw_rad() const;
  double speed_mps() const;
};

/// Linear and angular command from a panel input; zero with a reason when
/// motion is not allowed. Pure function, no ODE.
struct DriveCommand {
  double linear_mps = 0.0;
  double angular_radps = 0.0;
  bool enabled = false;
  std::string stop_reason;
};
DriveCommand map_controls(const ControlMapping& mapping, const ControlInput& input);

/// Arm joint rate targets (rad/s, order of ArmMapping::joints) and gripper
/// rate (m/s, + opens); zero with a reason when arm motion is not allowed.
/// Pure function, no ODE.
struct ArmCommand {
  std::vector<double> joint_radps;
  double gripper_mps = 0.0;
  bool enabled = false;
  std::string stop_reason;
};
ArmCommand map_arm_controls(const ControlMapping& mapping, const ControlInput& input);

class Simulation {
 public:
  static constexpr double kStepS = 0.001;

  Simulation(RobotDescription robot, WorldDescription world);
  ~Simulation();
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  void set_input(const ControlInput& input);
  /// Advances the world by one fixed step (1 ms).
  void step();
  double time_s() const;
  RobotSnapshot snapshot() const;
  const RobotDescription& robot() const;
  /// Events since the last call, oldest first; at most 4096 are kept
  /// between calls (later ones are dropped). Safe in the cyclic path: never
  /// throws.
  std::vector<SimEvent> take_events();
  /// Door angle (rad, + = swung about +z) or NaN for an unknown door.
  double door_angle_rad(const std::string& door) const;
  /// Centre of a movable object or a door panel (m), NaNs for an unknown name.
  std::array<double, 3> object_position_m(const std::string& object) const;

  /// The true pose of the base frame (the chassis centre; x forward, y left,
  /// z up) in the world. Safe in the cyclic path.
  Eigen::Isometry3d T_world_base() const;
  /// The true world pose of the robot file's camera `camera`
  /// (sensors.cameras), nullopt for an unknown name. Safe in the cyclic path.
  std::optional<Eigen::Isometry3d> T_world_camera(const std::string& camera) const;
  /// Distance (m) from `origin_world` along the unit `direction_world` to the
  /// first surface of the world — ground, ceiling, static boxes, props,
  /// walls, stairs, doors, objects; never the robot's own parts — or
  /// +infinity when there is none within max_range_m. ODE ray casting
  /// (dCreateRay + dCollide), the laser scanner's primitive. Safe in the cyclic path: no allocation,
  /// never throws. It reuses one ray geom: not from two threads at once.
  double cast_ray_m(const Eigen::Vector3d& origin_world, const Eigen::Vector3d& direction_world,
                    double max_range_m) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// How long the robot takes from `speed_mps` straight ahead (on flat, empty
/// ground) to standstill (|v| < 0.01 m/s, |ω| < 0.02 rad/s) once motion is
/// no longer allowed, measured by simulating it: the sim's share of every
/// stop-time bound.
double stop_time_s(const RobotDescription& robot, double speed_mps);

/// Number of diagnostic messages ODE has issued in this process (they are
/// counted, not printed).
int64_t ode_messages();

}  // namespace rise::sim
