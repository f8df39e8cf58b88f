#pragma once

// Faults of the simulated robot: physics (its drive and joints) and its
// sensors. Pure data; Simulation::set_fault applies them (no I/O, no clock:
// times are sim seconds, randomness is seeded, so a scenario replays bit for
// bit).
//
// | kind            | target                         | effect                                              |
// |-----------------|--------------------------------|-----------------------------------------------------|
// | motor_failure   | left, right (track_left, wheel_fl, ...) | that side's drive is stopped (belt/wheels held at 0) |
// | motor_weakness  | left, right                    | that side's speed × `value` (default 0.5)           |
// | track_slip      | left, right                    | that side's ground friction × `value` (default 0.2) |
// | weak_joint      | an arm joint (elbow_pitch, ...) or a door | its break load × `value` (default 0.3)   |
// | camera_blackout | a camera of sensors.cameras (or "" = every one) | camera_blacked_out() is true       |
// | scanner_noise   | laser (or "")                  | + N(0, `value` m, default 0.05) on every range      |
// | scanner_dropout | laser (or "")                  | each return lost with probability `value` (default 1) |

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace rise::sim {

enum class SimFaultKind {
  MotorFailure,
  MotorWeakness,
  TrackSlip,
  WeakJoint,
  CameraBlackout,
  ScannerNoise,
  ScannerDropout,
};
/// snake_case name ("motor_failure", ...).
const char* to_string(SimFaultKind kind);
std::optional<SimFaultKind> parse_sim_fault_kind(std::string_view name);

struct PhysicsFault {
  std::string id;      ///< the instance's name (clear names it)
  SimFaultKind kind = SimFaultKind::MotorFailure;
  std::string target;  ///< see the table
  double value = 0.0;  ///< 0 = the kind's default
  uint64_t seed = 0;
  double duration_s = 0.0;  ///< sim seconds from set_fault; 0 = until cleared
  // Set by Simulation::set_fault:
  double start_s = 0.0;
  double end_s = 0.0;  ///< 0 = until cleared
};

/// Seeded draws of the faults (splitmix64 of seed and index, as the
/// daemon's hil::seeded_uniform): uniform in [0, 1), standard normal.
double fault_uniform(uint64_t seed, uint64_t index);
double fault_normal(uint64_t seed, uint64_t index);

}  // namespace rise::sim
