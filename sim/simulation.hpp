#pragma once

// The ODE world with one skid-steer robot, stepped at a fixed 1 ms. Pure
// simulation: no clock, no I/O. The same inputs give the same trajectory,
// bit for bit.

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

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

struct RobotSnapshot {
  double time_s = 0.0;
  std::array<double, 3> position_m{};
  std::array<double, 4> orientation_wxyz{1, 0, 0, 0};
  std::array<double, 3> linear_velocity_mps{};     ///< base frame
  std::array<double, 3> angular_velocity_radps{};  ///< base frame
  std::vector<WheelState> wheels;                  ///< fl, fr, rl, rr
  std::vector<std::string> contacts;               ///< obstacles touched (not the ground)
  bool motors_enabled = false;
  std::string stop_reason;
  double commanded_linear_mps = 0.0;
  double commanded_angular_radps = 0.0;

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
