#pragma once

// Test helpers shared by the sensor tests: a drive panel and stepping.

#include <cmath>
#include <stdexcept>
#include <string>

#include "sim/simulation.hpp"

namespace rise::sim::testing {

/// Dead-man held, mode = drive, speed = fast, the given sticks (-1..1).
inline ControlInput drive_panel(float forward, float turn_right) {
  ControlInput in;
  in.fresh = true;
  in.failsafe = false;
  in.deadman = true;
  in.axes = {{"drive_y", forward}, {"drive_x", turn_right}};
  in.buttons = {{"estop", false}};
  in.switches = {{"mode", 0}, {"speed", 2}};
  in.switch_labels = {{"mode", "drive"}, {"speed", "fast"}};
  return in;
}

/// The message of the std::runtime_error that f() throws, or "no error".
template <typename F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

inline void run_for(Simulation& sim, double seconds) {
  const auto steps = static_cast<int>(std::lround(seconds / Simulation::kStepS));
  for (int i = 0; i < steps; ++i) sim.step();
}

}  // namespace rise::sim::testing
