#pragma once

// The ODE world with one or several robots (skid-steer or tracked,
// optionally with an arm), stepped at a fixed 1 ms. Pure simulation: no
// clock, no I/O. The same inputs give the same trajectories, bit for bit.
// Each step also records the semantic events a scenario engine scores
// (collisions, doors, regions, stairs, broken joints, tip-over) and the sound
// cues of the robot files' `sounds` sections.

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
#include "sim/sim_fault.hpp"
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
  CollisionStarted,  ///< a = robot part, b = entity (or the other robot's part); detail = impact speed
  CollisionStopped,  ///< a = robot part, b = entity or the other robot's part (no contact for 50 ms)
  DoorOpened,        ///< a = door; |angle| > 10°
  DoorClosed,        ///< a = door; |angle| < 5° again
  JointBroken,       ///< a = robot id or door, b = joint; detail = load
  RegionEntered,     ///< a = robot id, b = region; base inside the box
  RegionLeft,        ///< a = robot id, b = region
  ObjectMoved,       ///< a = object; > 5 cm from its start (once)
  StairsClimbed,     ///< a = robot id, b = stairs; base above the landing, on it
  TippedOver,        ///< a = robot id; base z axis > 60° from vertical
  CollisionContinues,  ///< a = robot part, b = entity; each full second a collision lasts, detail "N s"
  FaultInjected,  ///< a = robot id, b = fault id; detail "<kind> <target>"
  FaultCleared,   ///< a = robot id, b = fault id; detail "<kind> <target>: cleared | ended"
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

/// A sound for the player to play. Continuous cues are a robot's state
/// (RobotSnapshot::sounds, every snapshot, silent ones with gain 0);
/// one-shots come once, from Simulation::take_sound_cues().
struct SoundCue {
  double time_s = 0.0;
  std::string robot;   ///< robot id
  std::string name;    ///< the cue's key in the robot file's `sounds`
  std::string sample;  ///< what to play
  bool continuous = false;
  double gain = 0.0;   ///< 0..1, 0 = silent
  double pitch = 1.0;  ///< playback rate, 1 = as recorded
  std::string detail;  ///< what drives or set it off, e.g. "drive_speed 0.62" or "collision_started chassis crate 0.42 m/s"
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
  std::vector<SoundCue> sounds;  ///< the robot file's continuous cues, in file order
  std::vector<std::string> active_faults;  ///< "<id>: <kind> <target>" (sim_fault.hpp)

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

/// A urdf_tree robot's joint commands (order of ControlMapping::joints):
/// rad or m (position), rad/s or m/s (velocity), N·m or N (effort); each
/// joint's enabled is false (command 0) while its motion is not allowed.
/// Pure function, no ODE.
struct JointCommand {
  std::vector<double> values;
  std::vector<bool> enabled;
};
JointCommand map_joint_controls(const ControlMapping& mapping, const ControlInput& input);

/// One robot of a Simulation.
struct RobotSpec {
  /// Names the robot in events and sound cues: unique, not empty, no '/'.
  std::string id;
  RobotDescription description;
  /// Where it starts; default: the world's robot_start for the first robot,
  /// robot_starts[i - 1] for the i-th (from 0) after it.
  std::optional<RobotStart> start;
};

class Simulation {
 public:
  static constexpr double kStepS = 0.001;

  /// One robot, id = its description's name, at the world's robot_start.
  Simulation(RobotDescription robot, WorldDescription world);
  /// Several robots in one world (robot index = position in `robots`).
  /// With more than one, the robots' parts are named "<id>/<part>" in
  /// contacts and collision events (e.g. "r2/chassis"). Throws
  /// std::invalid_argument for no robots, a bad or repeated id, or a robot
  /// without a start pose. Not for the cyclic path.
  Simulation(std::vector<RobotSpec> robots, WorldDescription world);
  ~Simulation();
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  std::size_t robot_count() const;
  const std::string& robot_id(std::size_t robot) const;
  /// The index of the robot `id`; throws std::out_of_range for an unknown id.
  std::size_t robot_index(const std::string& id) const;

  /// The first robot's panel input (the one-robot API).
  void set_input(const ControlInput& input);
  /// Robot `robot`'s panel input; ignored for an index out of range. Safe
  /// in the cyclic path.
  void set_input(std::size_t robot, const ControlInput& input);
  /// Advances the world by one fixed step (1 ms).
  void step();
  double time_s() const;
  RobotSnapshot snapshot() const;  ///< the first robot
  RobotSnapshot snapshot(std::size_t robot) const;  ///< precondition: robot < robot_count()
  const RobotDescription& robot() const;  ///< the first robot
  const RobotDescription& robot(std::size_t robot) const;
  /// Events since the last call, oldest first; at most 4096 are kept
  /// between calls (later ones are dropped). Safe in the cyclic path: never
  /// throws.
  std::vector<SimEvent> take_events();
  /// One-shot sound cues of all robots since the last call, oldest first;
  /// at most 1024 are kept between calls. Safe in the cyclic path: never throws.
  std::vector<SoundCue> take_sound_cues();
  /// Door angle (rad, + = swung about +z) or NaN for an unknown door.
  double door_angle_rad(const std::string& door) const;
  /// Centre of a movable object or a door panel (m), NaNs for an unknown name.
  std::array<double, 3> object_position_m(const std::string& object) const;

  /// The true pose of robot `robot`'s base frame (the chassis centre; x
  /// forward, y left, z up) in the world (an index past the end reads the
  /// last robot). Safe in the cyclic path.
  Eigen::Isometry3d T_world_base(std::size_t robot = 0) const;
  /// A urdf_tree robot's link frames in the world, in the order of its
  /// description's tree.links (empty for other robots or an index out of
  /// range): what a viewer needs to draw the links' visual shapes. Safe in
  /// the cyclic path apart from the vector's allocation.
  std::vector<Eigen::Isometry3d> T_world_links(std::size_t robot = 0) const;
  /// The true world pose of the robot file's camera `camera`
  /// (sensors.cameras), nullopt for an unknown name. Safe in the cyclic path.
  std::optional<Eigen::Isometry3d> T_world_camera(const std::string& camera, std::size_t robot = 0) const;
  /// Applies a physics or sensor fault (sim/sim_fault.hpp) to robot
  /// `robot` from now for its duration_s; one with the same id replaces it.
  /// Records a FaultInjected event. Returns "" or why it was refused (an
  /// unknown robot, target or a kind the robot cannot take). Never throws.
  std::string set_fault(std::size_t robot, PhysicsFault fault);
  /// Clears robot `robot`'s fault `id` ("" = every one), each with a
  /// FaultCleared event; returns how many. Faults also end by themselves at
  /// their end_s, in step(). Never throws.
  std::size_t clear_fault(std::size_t robot, const std::string& id);
  /// Robot `robot`'s faults in effect (empty for an index out of range).
  std::vector<PhysicsFault> faults(std::size_t robot) const;
  /// True while a camera_blackout fault covers robot `robot`'s camera `camera`.
  bool camera_blacked_out(const std::string& camera, std::size_t robot = 0) const;

  /// Distance (m) from `origin_world` along the unit `direction_world` to the
  /// first surface of the world — ground, ceiling, static boxes, props,
  /// walls, stairs, doors, objects, the other robots; never robot
  /// `own_robot`'s parts — or +infinity when there is none within
  /// max_range_m. ODE ray casting (dCreateRay + dCollide), the laser
  /// scanner's primitive. Safe in the cyclic path: no allocation, never
  /// throws. It reuses one ray geom: not from two threads at once.
  double cast_ray_m(const Eigen::Vector3d& origin_world, const Eigen::Vector3d& direction_world,
                    double max_range_m, std::size_t own_robot = 0) const;

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
