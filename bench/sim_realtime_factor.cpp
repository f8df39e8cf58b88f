// Real-time factor of the simulator on one core: simulated seconds per wall
// second at the fixed 1 ms step (goal: >= 20x, so that one core can run
// several trainee stations with margin).
//
// The tracked EOD robot (sim/robots/tracked_eod.yaml) in the building world
// (sim/worlds/building.yaml) follows a fixed script: the arm swings and
// opens/closes the gripper, the robot drives through the door (pushing it
// open) into room B, turns, works the arm again, and so on. The skid4 robot
// runs the same script in the same world, side by side (its arm phases are
// standstill: skid4 has no arm). Then both robots at once in the same world:
// tracked_eod from the world's start, skid4 beside it 1.2 m to the south,
// each on the script (they meet at the door), the factor counted in world
// sim time. Prints sim time, wall time, the factor, the events the run
// produced and ODE's diagnostic count.
//
// Usage: bench_sim_realtime_factor [sim_seconds=60]

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "sim/simulation.hpp"

namespace {

struct Result {
  double sim_s = 0.0;
  double wall_s = 0.0;
  std::size_t events = 0;
  std::map<std::string, int> kinds;
  double travelled_m = 0.0;
  std::size_t sounds = 0;  // one-shot sound cues
};

// The scripted panel at sim time t (a 20 s cycle).
rise::sim::ControlInput script(double t) {
  rise::sim::ControlInput in;
  in.fresh = true;
  in.failsafe = false;
  in.deadman = true;
  in.buttons = {{"estop", false}, {"gripper_open", false}, {"gripper_close", false}};
  const double c = std::fmod(t, 20.0);
  const bool arm = c < 3.0 || (c >= 13.0 && c < 16.0);
  in.switches = {{"mode", arm ? 1 : 0}, {"speed", 1}};
  in.switch_labels = {{"mode", arm ? "arm" : "drive"}, {"speed", "medium"}};
  if (arm) {
    in.axes = {{"arm_x", static_cast<float>(0.6 * std::sin(2.0 * t))},
               {"arm_y", static_cast<float>(0.8 * std::sin(1.3 * t))},
               {"arm_twist", static_cast<float>(0.7 * std::cos(1.7 * t))}};
    in.buttons[std::fmod(t, 2.0) < 1.0 ? "gripper_open" : "gripper_close"] = true;
  } else if (c < 11.0) {
    in.axes = {{"drive_y", 1.0f}, {"drive_x", 0.0f}};  // ahead: the door is 3 m in front of the start
  } else if (c < 13.0) {
    in.axes = {{"drive_y", 0.0f}, {"drive_x", 0.6f}};  // turn in place
  } else {
    in.axes = {{"drive_y", 0.6f}, {"drive_x", -0.3f}};  // a curve
  }
  return in;
}

Result run(const std::vector<std::string>& robot_files, const rise::sim::WorldDescription& world,
           double sim_seconds) {
  std::vector<rise::sim::RobotSpec> specs;
  for (std::size_t i = 0; i < robot_files.size(); ++i) {
    const auto& start = world.robot_start_m;
    specs.push_back(rise::sim::RobotSpec{"r" + std::to_string(i), rise::sim::load_robot_description(robot_files[i]),
                                         rise::sim::RobotStart{{start[0], start[1] - 1.2 * static_cast<double>(i)},
                                                               world.robot_start_yaw_rad}});
  }
  rise::sim::Simulation sim(specs, world);
  Result r;
  const auto steps = static_cast<long>(std::lround(sim_seconds / rise::sim::Simulation::kStepS));
  const auto start = std::chrono::steady_clock::now();
  for (long i = 0; i < steps; ++i) {
    // The LCM adapter sets the inputs every step too.
    for (std::size_t k = 0; k < sim.robot_count(); ++k) sim.set_input(k, script(sim.time_s()));
    sim.step();
    r.sounds += sim.take_sound_cues().size();
    for (const auto& e : sim.take_events()) {
      ++r.events;
      ++r.kinds[rise::sim::to_string(e.kind)];
    }
  }
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.sim_s = sim.time_s();
  const auto s = sim.snapshot();
  r.travelled_m = std::hypot(s.position_m[0] - world.robot_start_m[0], s.position_m[1] - world.robot_start_m[1]);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  const double sim_seconds = argc > 1 ? std::atof(argv[1]) : 60.0;
  if (!(sim_seconds > 0)) {
    std::fprintf(stderr, "usage: %s [sim_seconds>0]\n", argv[0]);
    return 2;
  }
  const std::string root = RISE_SOURCE_DIR;
  const auto world = rise::sim::load_world_description(root + "/sim/worlds/building.yaml");
  std::printf("sim real-time factor, building world, 1 ms step, one core, %.0f s simulated per robot\n", sim_seconds);
  std::printf("%-14s %10s %10s %10s %12s %8s %14s\n", "robot", "sim_s", "wall_s", "RTF", "steps/s", "events",
              "end_from_start_m");
  const std::string tracked = root + "/sim/robots/tracked_eod.yaml", skid4 = root + "/sim/robots/skid4.yaml";
  const std::pair<const char*, std::vector<std::string>> runs[] = {
      {"tracked_eod", {tracked}}, {"skid4", {skid4}}, {"tracked+skid4", {tracked, skid4}}};
  for (const auto& [label, files] : runs) {
    const int64_t ode_before = rise::sim::ode_messages();
    const Result r = run(files, world, sim_seconds);
    std::printf("%-14s %10.1f %10.3f %9.1fx %12.0f %8zu %14.2f\n", label, r.sim_s, r.wall_s, r.sim_s / r.wall_s,
                r.sim_s / rise::sim::Simulation::kStepS / r.wall_s, r.events, r.travelled_m);
    std::printf("%-14s", "");
    for (const auto& [kind, n] : r.kinds) std::printf(" %s×%d", kind.c_str(), n);
    std::printf(" sound one-shots×%zu; ODE diagnostics %lld\n", r.sounds,
                static_cast<long long>(rise::sim::ode_messages() - ode_before));
  }
  std::printf("goal: RTF >= 20x; ODE diagnostics during the runs: %lld\n",
              static_cast<long long>(rise::sim::ode_messages()));
  return 0;
}
