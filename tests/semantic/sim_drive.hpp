#pragma once

// Driving the tracked robot in a generated world, for the tests that check
// a world rise-semantic wrote can be driven: the operator's input, stepping
// the simulation, its events, the world's doorways.

#include <Eigen/Core>

#include <cmath>
#include <string>
#include <vector>

#include "sim/simulation.hpp"
#include "sim/world_description.hpp"
#include "tests/semantic/ground_truth.hpp"

namespace rise::semantic::testing {

inline rise::sim::ControlInput drive(float forward, int speed) {
  static const char* const kSpeeds[] = {"slow", "medium", "fast"};
  rise::sim::ControlInput in;
  in.fresh = true;
  in.failsafe = false;
  in.deadman = true;
  in.buttons = {{"estop", false}, {"gripper_open", false}, {"gripper_close", false}};
  in.switches = {{"mode", 0}, {"speed", speed}};
  in.switch_labels = {{"mode", "drive"}, {"speed", kSpeeds[speed]}};
  in.axes = {{"drive_y", forward}, {"drive_x", 0.0f}};
  return in;
}

// Steps `seconds` of sim time or until an event of `kind` naming `a` or
// `b` (when `stop_on` is set); every event lands in `log`.
inline void run(rise::sim::Simulation& sim, double seconds, std::vector<rise::sim::SimEvent>& log,
         rise::sim::SimEventKind kind = rise::sim::SimEventKind::CollisionStarted, const std::string& name = "",
         bool stop_on = false) {
  const auto steps = static_cast<long>(std::lround(seconds / rise::sim::Simulation::kStepS));
  for (long i = 0; i < steps; ++i) {
    sim.step();
    for (auto& e : sim.take_events()) {
      log.push_back(e);
      if (stop_on && e.kind == kind && (e.a == name || e.b == name)) return;
    }
  }
}

inline bool any(const std::vector<rise::sim::SimEvent>& log, rise::sim::SimEventKind kind, const std::string& name = "") {
  for (const auto& e : log)
    if (e.kind == kind && (name.empty() || e.a == name || e.b == name)) return true;
  return false;
}

// A doorway of the generated world: the middle of its clear gap and the
// unit normal of its wall line, and the hinged door's name (or "").
struct Doorway {
  Eigen::Vector2d center, along, normal;
  double width_m = 0.0;
  std::string door;
};

inline std::vector<Doorway> doorways(const rise::sim::WorldDescription& w) {
  std::vector<Doorway> out;
  for (const auto& d : w.doors) {
    const Eigen::Vector2d along(std::cos(d.yaw_rad), std::sin(d.yaw_rad));
    out.push_back({v2(d.hinge_m) + along * d.width_m / 2, along, {-along.y(), along.x()}, d.width_m, d.name});
  }
  for (const auto& wall : w.walls) {
    const Eigen::Vector2d a = v2(wall.from_m), along = (v2(wall.to_m) - a).normalized();
    for (const auto& o : wall.openings)
      out.push_back({a + along * (o.at_m + o.width_m / 2), along, {-along.y(), along.x()}, o.width_m, ""});
  }
  return out;
}

}  // namespace rise::semantic::testing
