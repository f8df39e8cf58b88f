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
// Issue 5's "the same with a world generated from scans": the tracked robot
// on the same script in the world the semantic engine makes of the
// building (issue 6): the simulator's laser scans it from 10 stops (room A,
// the doorway, the corridor, the foot of the stairs), the semantic
// pipeline (6D SLAM, segmentation, world_yaml — what `rise-semantic map`
// writes as world.yaml) turns the scans into a world file, loaded by the
// simulator's own reader; or the world file given as the second argument.
// Its robot start is the exporter's (in front of the first door found,
// facing it), so the script pushes through that door too.
//
// Usage: bench_sim_realtime_factor [sim_seconds=60] [scan_world.yaml]

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "semantic/map_pipeline.hpp"
#include "sim/laser_scanner.hpp"
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

// The building as the semantic engine sees it: scans from 10 stops (the
// tracked robot's laser at 1° × 120 lines, sensor frame, true poses as the
// guess), mapped, segmented and exported as a world file, read back.
rise::sim::WorldDescription scan_generated_world(const std::string& root, double& generate_s) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto robot = rise::sim::load_robot_description(root + "/sim/robots/tracked_eod.yaml");
  rise::sim::LaserDescription laser = *robot.sensors.laser;
  laser.resolution_rad = M_PI / 180.0;
  laser.rotating->steps = 120;
  rise::sim::LaserScanner scanner(laser, 3);
  const double stops[][3] = {{0.0, 0.0, 0.0},   {-1.2, -1.6, 40.0}, {-2.6, -2.0, 90.0}, {-2.3, 0.2, 80.0},
                             {-2.25, 1.9, 90.0}, {-2.3, 3.6, 60.0},  {-2.6, 4.4, 0.0},   {-1.2, 4.2, -10.0},
                             {-0.5, 3.5, 20.0},  {-0.8, 4.6, -5.0}};
  std::vector<rise::semantic::Scan> scans;
  for (const auto& st : stops) {
    auto w = rise::sim::load_world_description(root + "/sim/worlds/building.yaml");
    w.robot_start_m = {st[0], st[1]};
    w.robot_start_yaw_rad = st[2] * M_PI / 180.0;
    rise::sim::Simulation sim(robot, w);
    const rise::sim::LaserScan scan = scanner.scan(sim);
    rise::semantic::Scan s;
    s.name = "stop" + std::to_string(scans.size());
    s.cloud.points = scan.points_sensor;
    s.T_world_scan = scan.T_world_sensor;
    scans.push_back(std::move(s));
  }
  rise::semantic::MapSettings settings;
  settings.slam.icp.threads = 1;  // one core, as the simulator's runs
  const rise::semantic::MapResult map = rise::semantic::build_map(std::move(scans), settings);
  rise::semantic::ExportSettings exports;
  exports.world_name = "scanned_building";
  const std::string yaml = rise::semantic::world_yaml(map.net, exports);
  generate_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return rise::sim::parse_world_description(yaml, "scanned_building.yaml");
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
  double generate_s = 0.0;
  const std::string scan_world_file = argc > 2 ? argv[2] : "";
  const auto scan_world = scan_world_file.empty() ? scan_generated_world(root, generate_s)
                                                  : rise::sim::load_world_description(scan_world_file);
  if (scan_world_file.empty())
    std::printf("scan-generated world: 10 scans of the building mapped by the semantic pipeline in %.2f s: "
                "%zu walls, %zu doors, %zu stairs, %zu props\n",
                generate_s, scan_world.walls.size(), scan_world.doors.size(), scan_world.stairs.size(),
                scan_world.props.size());
  else
    std::printf("scan-generated world: %s\n", scan_world_file.c_str());
  std::printf("sim real-time factor, building world, 1 ms step, one core, %.0f s simulated per robot\n", sim_seconds);
  std::printf("%-14s %10s %10s %10s %12s %8s %14s\n", "robot", "sim_s", "wall_s", "RTF", "steps/s", "events",
              "end_from_start_m");
  const std::string tracked = root + "/sim/robots/tracked_eod.yaml", skid4 = root + "/sim/robots/skid4.yaml";
  struct Run {
    const char* label;
    std::vector<std::string> files;
    const rise::sim::WorldDescription* world;
  };
  const Run runs[] = {{"tracked_eod", {tracked}, &world},
                      {"skid4", {skid4}, &world},
                      {"tracked+skid4", {tracked, skid4}, &world},
                      {"tracked@scans", {tracked}, &scan_world}};
  for (const auto& [label, files, w] : runs) {
    const int64_t ode_before = rise::sim::ode_messages();
    const Result r = run(files, *w, sim_seconds);
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
