#pragma once

// What the simulator needs to know about a robot: its body, its wheels, and
// its control mapping — which panel controls drive which actuators.
// Loaded from YAML (sim/robots/skid4.yaml).

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace rise::sim {

struct ChassisDescription {
  std::array<double, 3> size_m{0.8, 0.5, 0.25};  ///< length (x), width (y), height (z)
  double mass_kg = 40.0;
  double clearance_m = 0.05;  ///< ground to chassis bottom at rest
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
};

/// One axis of motion driven by a panel axis: command = value · max.
struct AxisMapping {
  std::string axis;
  double max = 0.0;  ///< m/s for linear, rad/s for angular
  bool invert = false;
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
};

struct RobotDescription {
  std::string name;
  std::string file;
  ChassisDescription chassis;
  WheelsDescription wheels;
  ControlMapping control;
};

/// Loads a robot file. Throws std::runtime_error "file:line: key: message"
/// for unknown keys, missing or out-of-range values.
RobotDescription load_robot_description(const std::string& path);
RobotDescription parse_robot_description(const std::string& text, const std::string& file);

}  // namespace rise::sim
