// rise-sim: the ODE simulator as an LCM node. Subscribes the trainee's
// PanelState, steps the world at a fixed 1 ms, publishes RobotState, the
// console feedback (the speed display) and every simulation event
// (SimEvent on rise/<id>/sim_event). With --scan-dir it also writes the
// robot's 3D laser scans as PCD files with their true pose beside them.
// SimControl on rise/<id>/sim_control pauses, resumes, single-steps and
// resets the simulation; each handled command is answered with a SimEvent.

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <poll.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <optional>
#include <thread>
#include <vector>

#include "rise_msgs/PanelFeedback.hpp"
#include "rise_msgs/PanelState.hpp"
#include "rise_msgs/RobotState.hpp"
#include "rise_msgs/SimControl.hpp"
#include "rise_msgs/SimEvent.hpp"
#include "sim/laser_scanner.hpp"
#include "sim/simulation.hpp"

namespace {
volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string source_file(const std::string& relative) {
  if (std::filesystem::exists(relative)) return relative;
  const auto p = std::filesystem::path(RISE_SOURCE_DIR) / relative;
  return std::filesystem::exists(p) ? p.string() : relative;
}

// The latest panel state, turned into what the robot's control mapping reads.
struct PanelListener {
  rise::sim::ControlInput input;
  std::chrono::steady_clock::time_point received{};
  bool any = false;
  int64_t count = 0;

  void on(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::PanelState* m) {
    input.axes.clear();
    input.buttons.clear();
    input.switches.clear();
    input.switch_labels.clear();
    for (const auto& a : m->axes) input.axes[a.name] = a.value;
    for (const auto& b : m->buttons) input.buttons[b.name] = b.pressed;
    for (const auto& s : m->switches) {
      input.switches[s.name] = s.position;
      input.switch_labels[s.name] = s.label;
    }
    input.failsafe = m->failsafe;
    input.deadman = m->deadman;
    received = std::chrono::steady_clock::now();
    any = true;
    ++count;
  }
};

// One step command advances at most an hour of sim time: the loop does not
// take LCM messages while it steps.
constexpr int32_t kMaxControlSteps = 3600 * 1000;

// Commands in arrival order, applied by the main loop between steps.
struct ControlListener {
  std::vector<rise_msgs::SimControl> pending;
  void on(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::SimControl* m) { pending.push_back(*m); }
};

rise_msgs::RobotState to_message(const rise::sim::RobotSnapshot& s, const std::string& robot_id) {
  rise_msgs::RobotState m;
  m.utime = wall_us();
  m.sim_time_s = s.time_s;
  m.robot_id = robot_id;
  for (int i = 0; i < 3; ++i) {
    m.position_m[i] = s.position_m[static_cast<std::size_t>(i)];
    m.linear_velocity_mps[i] = s.linear_velocity_mps[static_cast<std::size_t>(i)];
    m.angular_velocity_radps[i] = s.angular_velocity_radps[static_cast<std::size_t>(i)];
  }
  for (int i = 0; i < 4; ++i) m.orientation_wxyz[i] = s.orientation_wxyz[static_cast<std::size_t>(i)];
  for (const auto& w : s.wheels) {
    m.joint_names.push_back(w.name);
    m.joint_positions.push_back(w.position_rad);
    m.joint_velocities.push_back(w.velocity_radps);
    m.joint_efforts.push_back(w.effort_nm);
  }
  for (const auto& j : s.joints) {
    m.joint_names.push_back(j.name);
    m.joint_positions.push_back(j.position);
    m.joint_velocities.push_back(j.velocity);
    m.joint_efforts.push_back(j.effort);
  }
  m.num_joints = static_cast<int16_t>(m.joint_names.size());
  m.damage = static_cast<float>(s.damage);
  m.battery = 1.0f;
  m.motors_enabled = s.motors_enabled;
  m.stop_reason = s.stop_reason;
  m.contacts = s.contacts;
  m.num_contacts = static_cast<int16_t>(m.contacts.size());
  return m;
}

rise_msgs::SimEvent to_message(const rise::sim::SimEvent& e, const std::string& robot_id) {
  rise_msgs::SimEvent m;
  m.utime = wall_us();
  m.sim_time_s = e.time_s;
  m.robot_id = robot_id;
  m.kind = rise::sim::to_string(e.kind);
  m.a = e.a;
  m.b = e.b;
  m.detail = e.detail;
  return m;
}

// Contacts come and go all the time (a track on step noses); the rest is
// what a trainer wants to see in the log.
void log_event(const rise::sim::SimEvent& e) {
  const bool contact =
      e.kind == rise::sim::SimEventKind::CollisionStarted || e.kind == rise::sim::SimEventKind::CollisionStopped ||
      e.kind == rise::sim::SimEventKind::CollisionContinues;
  spdlog::log(contact ? spdlog::level::debug : spdlog::level::info, "event {:.3f} s: {} {} {} {}", e.time_s,
              rise::sim::to_string(e.kind), e.a, e.b, e.detail);
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rise-sim: ODE robot simulator driven by PanelState over LCM"};
  std::string robot_file = "sim/robots/skid4.yaml";
  std::string world_file;
  std::string id = "t1";
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  bool fast = false;
  double duration_s = 0.0;
  double state_hz = 50.0;
  int panel_timeout_ms = 100;
  std::string log_level = "info";
  std::string scan_dir;
  double scan_every_s = 0.0;
  std::string scan_format = "binary";
  app.add_option("--robot", robot_file, "robot file (YAML)")->capture_default_str();
  app.add_option("--world", world_file, "world file (YAML); default: the built-in yard");
  app.add_option("--id", id, "trainee/station id used in channel names")->capture_default_str();
  app.add_option("--lcm", lcm_url, "LCM URL")->capture_default_str();
  app.add_flag("--fast", fast, "run as fast as possible instead of real-time paced");
  app.add_option("--duration", duration_s, "stop after S simulated seconds (0: run until SIGINT/SIGTERM)");
  app.add_option("--state-hz", state_hz, "RobotState rate")->capture_default_str()->check(CLI::Range(1.0, 1000.0));
  app.add_option("--panel-timeout-ms", panel_timeout_ms, "stop the robot when no PanelState arrives for this long")
      ->capture_default_str()
      ->check(CLI::Range(1, 10000));
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error")->capture_default_str();
  app.add_option("--scan-dir", scan_dir, "write a laser scan (scan_NNNN.pcd + .pose) here at start");
  app.add_option("--scan-every", scan_every_s, "and every S seconds of sim time (0: only at start)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--scan-format", scan_format, "PCD DATA: ascii or binary")
      ->capture_default_str()
      ->check(CLI::IsMember({"ascii", "binary"}));
  CLI11_PARSE(app, argc, argv);
  spdlog::set_level(spdlog::level::from_str(log_level));

  rise::sim::RobotDescription robot;
  rise::sim::WorldDescription world = rise::sim::default_world();
  try {
    robot = rise::sim::load_robot_description(source_file(robot_file));
    if (!world_file.empty()) world = rise::sim::load_world_description(source_file(world_file));
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }

  lcm::LCM lcm(lcm_url);
  if (!lcm.good()) {
    spdlog::error("cannot open LCM at {}", lcm_url);
    return 2;
  }
  const std::string panel_channel = "rise/" + id + "/panel_state";
  const std::string state_channel = "rise/" + id + "/robot_state";
  const std::string feedback_channel = "rise/" + id + "/panel_feedback";
  const std::string event_channel = "rise/" + id + "/sim_event";
  PanelListener panel;
  // Only the newest panel state matters to the physics; a short queue keeps
  // a stalled sim from acting on old sticks.
  lcm.subscribe(panel_channel, &PanelListener::on, &panel)->setQueueCapacity(8);

  std::optional<rise::sim::LaserScanner> scanner;
  if (!scan_dir.empty()) {
    if (!robot.sensors.laser) {
      spdlog::error("--scan-dir: {} has no sensors.laser", robot.file);
      return 2;
    }
    std::error_code ec;
    std::filesystem::create_directories(scan_dir, ec);
    if (ec) {
      spdlog::error("--scan-dir {}: {}", scan_dir, ec.message());
      return 2;
    }
    scanner.emplace(*robot.sensors.laser, robot.sensors.seed);
  }
  int scans = 0;
  double next_scan_s = 0.0;
  const auto format = scan_format == "ascii" ? rise::sim::PcdFormat::Ascii : rise::sim::PcdFormat::Binary;

  const std::string control_channel = "rise/" + id + "/sim_control";
  ControlListener control;
  lcm.subscribe(control_channel, &ControlListener::on, &control)->setQueueCapacity(64);

  // Reset rebuilds the whole world and robot: a Simulation is not assignable.
  std::optional<rise::sim::Simulation> sim;
  sim.emplace(robot, world);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  spdlog::info("rise-sim ready: robot '{}' ({}), world '{}', {} on {}, {} → {}, {}; control on {}", robot.name,
               robot.file, world.name, fast ? "as fast as possible" : "real time", lcm_url, panel_channel,
               state_channel, event_channel, control_channel);

  const int steps_per_state = std::max(1, static_cast<int>(std::lround(1.0 / (state_hz * rise::sim::Simulation::kStepS))));
  const int steps_per_feedback = 100;  // 10 Hz
  const auto start = std::chrono::steady_clock::now();
  const auto state_period = std::chrono::microseconds(static_cast<int64_t>(std::lround(1e6 / state_hz)));
  const auto timeout = std::chrono::milliseconds(panel_timeout_ms);
  std::string last_reason = "-";
  int64_t step = 0;  // since start or the last reset
  // Real-time pacing restarts from here after a pause, step or reset.
  auto paced_from = start;
  int64_t paced_steps = 0;
  bool paused = false;
  auto next_paused_state = start;

  const auto publish_state = [&] {
    const auto snap = sim->snapshot();
    const auto msg = to_message(snap, robot.name);
    lcm.publish(state_channel, &msg);
    if (snap.stop_reason != last_reason) {
      if (snap.motors_enabled) spdlog::info("motors enabled");
      else spdlog::info("motors stopped: {}", snap.stop_reason);
      last_reason = snap.stop_reason;
    }
    return std::make_pair(snap, msg.utime);
  };

  // One 1 ms step with everything that hangs on it: scans, events, state.
  const auto advance = [&] {
    // Stop-and-go scanning: the whole scan at one instant of sim time.
    if (scanner && sim->time_s() >= next_scan_s - 1e-9) {
      char name[32];
      std::snprintf(name, sizeof name, "scan_%04d", scans++);
      const auto stem = (std::filesystem::path(scan_dir) / name).string();
      const auto scan = scanner->scan(*sim);
      try {
        rise::sim::write_scan(stem, scan, format);
        spdlog::info("scan {:.3f} s: {}.pcd, {} points", scan.time_s, stem, scan.points_sensor.size());
      } catch (const std::exception& e) {
        spdlog::error("{}", e.what());
      }
      next_scan_s = scan_every_s > 0 ? next_scan_s + scan_every_s : std::numeric_limits<double>::infinity();
    }

    rise::sim::ControlInput input = panel.input;
    input.fresh = panel.any && std::chrono::steady_clock::now() - panel.received <= timeout;
    sim->set_input(input);
    sim->step();
    ++step;
    for (const auto& e : sim->take_events()) {
      log_event(e);
      const auto msg = to_message(e, robot.name);
      lcm.publish(event_channel, &msg);
    }

    if (step % steps_per_state == 0) {
      const auto [snap, utime] = publish_state();
      if (step % steps_per_feedback == 0) {
        rise_msgs::PanelFeedback fb;
        fb.utime = utime;
        fb.panel_id = "";
        fb.num_leds = 0;  // the bridge owns power/fault/e-stop LEDs
        fb.display_names = {"speed"};
        fb.display_values = {static_cast<float>(snap.speed_mps())};
        fb.num_displays = 1;
        fb.buzzer = 0;
        fb.rumble = 0.0f;
        lcm.publish(feedback_channel, &fb);
      }
    }
  };

  const auto answer = [&](const rise_msgs::SimControl& c, const std::string& kind, const std::string& what) {
    rise_msgs::SimEvent msg;
    msg.utime = wall_us();
    msg.sim_time_s = sim->time_s();
    msg.robot_id = robot.name;
    msg.kind = kind;
    msg.a = c.issuer;
    msg.detail = "seq " + std::to_string(c.seq) + (what.empty() ? "" : ": " + what);
    spdlog::info("sim_control {:.3f} s: {} from '{}' {}", msg.sim_time_s, kind, c.issuer, msg.detail);
    lcm.publish(event_channel, &msg);
  };

  const auto apply = [&](const rise_msgs::SimControl& c) {
    if (c.command == "pause") {
      paused = true;
      next_paused_state = std::chrono::steady_clock::now();
      answer(c, "sim_paused", "");
    } else if (c.command == "resume") {
      paused = false;
      answer(c, "sim_resumed", "");
    } else if (c.command == "step" && c.steps >= 1 && c.steps <= kMaxControlSteps) {
      paused = true;
      for (int32_t i = 0; i < c.steps && !g_stop; ++i) advance();
      answer(c, "sim_stepped", std::to_string(c.steps) + " steps of 1 ms");
      publish_state();
      next_paused_state = std::chrono::steady_clock::now() + state_period;
    } else if (c.command == "reset") {
      sim.emplace(robot, world);
      step = 0;
      next_scan_s = 0.0;
      last_reason = "-";
      answer(c, "sim_reset", "world and robot rebuilt, robot at the start pose");
      publish_state();
      next_paused_state = std::chrono::steady_clock::now() + state_period;
    } else {
      answer(c, "sim_control_refused",
             "command '" + c.command + "' with steps " + std::to_string(c.steps) + ": expected pause, resume, step " +
                 "(steps 1.." + std::to_string(kMaxControlSteps) + ") or reset");
      return;
    }
    paced_from = std::chrono::steady_clock::now();
    paced_steps = 0;
  };

  while (!g_stop && (duration_s <= 0 || sim->time_s() < duration_s)) {
    // Take every waiting LCM message without blocking the physics.
    pollfd pfd{lcm.getFileno(), POLLIN, 0};
    while (::poll(&pfd, 1, 0) > 0) lcm.handle();
    for (const auto& c : control.pending) apply(c);
    control.pending.clear();

    if (paused) {
      // No stepping; RobotState still goes out, with the same sim time.
      if (std::chrono::steady_clock::now() >= next_paused_state) {
        publish_state();
        next_paused_state += state_period;
      }
      ::poll(&pfd, 1, 1);
      continue;
    }
    advance();
    ++paced_steps;
    if (!fast) std::this_thread::sleep_until(paced_from + std::chrono::microseconds(paced_steps * 1000));
  }
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  spdlog::info("rise-sim stopped: {:.1f} s simulated in {:.1f} s ({:.1f}x real time), {} panel states", sim->time_s(),
               wall_s, wall_s > 0 ? sim->time_s() / wall_s : 0.0, panel.count);
  return 0;
}
