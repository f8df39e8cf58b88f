// rise-sim: the ODE simulator as an LCM node, one world with one or several
// robots. For each robot it subscribes the trainee's PanelState, and
// publishes RobotState, the console feedback (the speed display), every
// simulation event (SimEvent on rise/<id>/sim_event) and the robot file's
// sound cues (SoundCue on rise/<id>/sound); the world steps at a fixed 1 ms.
// With --scan-dir it also writes the first robot's 3D laser scans as PCD
// files with their true pose beside them. SimControl on any robot's
// rise/<id>/sim_control pauses, resumes, single-steps and resets the whole
// world; each handled command is answered with a SimEvent on that robot's
// sim_event.

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <poll.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <set>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <thread>
#include <vector>

#include "cli/command_line.hpp"
#include "msgs/channels.hpp"
#include "msgs/clock.hpp"
#include "msgs/clock_offset.hpp"
#include "msgs/command_auth.hpp"
#include "msgs/lcm_decode.hpp"
#include "msgs/publisher_session.hpp"
#include "panels/data_path.hpp"
#include "rise_msgs/FaultCommand.hpp"
#include "rise_msgs/PanelFeedback.hpp"
#include "rise_msgs/PanelState.hpp"
#include "rise_msgs/RobotState.hpp"
#include "rise_msgs/SimControl.hpp"
#include "rise_msgs/SimEvent.hpp"
#include "rise_msgs/SoundCue.hpp"
#include "rise_msgs/TrainingControl.hpp"
#include "sim/laser_scanner.hpp"
#include "sim/simulation.hpp"

namespace {
volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

// A robot or world file as given, else installed or in the source tree.
std::string source_file(const std::string& relative) { return rise::panels::find_data_file(relative); }

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

// Commands from every robot's control channel, in arrival order, applied by
// the main loop between steps; each remembers the robot it came in for.
struct ControlListener {
  std::vector<std::pair<std::size_t, rise_msgs::SimControl>>* pending = nullptr;
  std::size_t robot = 0;
  void on(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::SimControl* m) {
    pending->emplace_back(robot, *m);
  }
};

// Signed instructor commands (msgs/command_auth.hpp) of every robot's
// channels, in arrival order, verified and applied between steps.
struct InstructorListener {
  std::vector<std::pair<std::size_t, rise_msgs::FaultCommand>>* faults = nullptr;
  std::vector<std::pair<std::size_t, rise_msgs::TrainingControl>>* training = nullptr;
  std::size_t robot = 0;
  void on_fault(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::FaultCommand* m) {
    faults->emplace_back(robot, *m);
  }
  void on_training(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::TrainingControl* m) {
    training->emplace_back(robot, *m);
  }
};

// One --robot: ID=FILE[@x,y,yaw_deg] or FILE[@x,y,yaw_deg].
struct RobotArg {
  std::string id;  // empty: the plain FILE form
  std::string file;
  std::optional<rise::sim::RobotStart> start;
};

// Throws std::invalid_argument naming the flag's value and what is wrong.
RobotArg parse_robot_arg(const std::string& text) {
  RobotArg a;
  std::string rest = text;
  if (const auto eq = rest.find('='); eq != std::string::npos) {
    a.id = rest.substr(0, eq);
    rest = rest.substr(eq + 1);
    if (a.id.empty() || a.id.find('/') != std::string::npos)
      throw std::invalid_argument("--robot " + text + ": the id before '=' must be non-empty, without '/'");
  }
  if (const auto at = rest.rfind('@'); at != std::string::npos) {
    const std::string pose = rest.substr(at + 1);
    rest = rest.substr(0, at);
    std::vector<double> v;
    std::size_t from = 0;
    while (true) {
      const auto comma = pose.find(',', from);
      const std::string part = pose.substr(from, comma == std::string::npos ? std::string::npos : comma - from);
      char* end = nullptr;
      const double x = std::strtod(part.c_str(), &end);
      if (part.empty() || end != part.c_str() + part.size() || !std::isfinite(x)) v.clear();
      else v.push_back(x);
      if (v.empty() || comma == std::string::npos) break;
      from = comma + 1;
    }
    if (v.size() != 2 && v.size() != 3)
      throw std::invalid_argument("--robot " + text + ": start pose '" + pose + "': expected x,y or x,y,yaw_deg");
    a.start = rise::sim::RobotStart{{v[0], v[1]}, v.size() == 3 ? v[2] * M_PI / 180.0 : 0.0};
  }
  if (rest.empty()) throw std::invalid_argument("--robot " + text + ": no robot file");
  a.file = rest;
  return a;
}

rise_msgs::RobotState to_message(const rise::sim::RobotSnapshot& s, const std::string& robot_id) {
  rise_msgs::RobotState m;
  m.utime = rise::msgs::wall_us();
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
  for (int i = 0; i < 3; ++i) m.gripper_position_m[i] = s.gripper_position_m[static_cast<std::size_t>(i)];
  m.num_objects = 0;
  m.active_faults = s.active_faults;
  m.num_faults = static_cast<int16_t>(m.active_faults.size());
  return m;
}

// The world's movable objects, for task executors that score where they are.
void add_objects(rise_msgs::RobotState& m, const rise::sim::Simulation& sim, const rise::sim::WorldDescription& world) {
  for (const auto& o : world.objects) {
    const auto p = sim.object_position_m(o.name);
    m.object_names.push_back(o.name);
    m.object_positions_m.push_back({p[0], p[1], p[2]});
  }
  m.num_objects = static_cast<int16_t>(m.object_names.size());
}

rise_msgs::SoundCue to_message(const rise::sim::SoundCue& c) {
  rise_msgs::SoundCue m;
  m.utime = rise::msgs::wall_us();
  m.sim_time_s = c.time_s;
  m.robot_id = c.robot;
  m.name = c.name;
  m.sample = c.sample;
  m.continuous = c.continuous;
  m.gain = static_cast<float>(c.gain);
  m.pitch = static_cast<float>(c.pitch);
  m.detail = c.detail;
  return m;
}

rise_msgs::SimEvent to_message(const rise::sim::SimEvent& e, const std::string& robot_id) {
  rise_msgs::SimEvent m;
  m.utime = rise::msgs::wall_us();
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
// Whether event `e` names robot `id` (as the robot, or "<id>/<part>").
bool names_robot(const rise::sim::SimEvent& e, const std::string& id) {
  const std::string part = id + "/";
  return e.a == id || e.b == id || e.a.rfind(part, 0) == 0 || e.b.rfind(part, 0) == 0;
}

// One robot of the world and its LCM side.
struct Station {
  std::string id;  // channel id: rise/<id>/...
  rise::sim::RobotSpec spec;
  std::string panel_channel, state_channel, feedback_channel, event_channel, control_channel, sound_channel;
  std::string fault_channel, training_channel;
  PanelListener panel;
  ControlListener control;
  InstructorListener instructor;
  std::string last_reason = "-";
};

// The command line.
struct Options {
  std::vector<std::string> robot_args{"sim/robots/skid4.yaml"};
  std::string world_file;
  std::string id = "t1";
  std::string lcm_url = rise::msgs::kDefaultLcmUrl;
  bool fast = false;
  double duration_s = 0.0;
  double state_hz = 50.0;
  int panel_timeout_ms = 100;
  std::string instructor_key_file;
  double command_window_s = 5.0;
  std::string log_level = "info";
  bool allow_duplicate_id = false;
  std::string scan_dir;
  double scan_every_s = 0.0;
  std::string scan_format = "binary";
};

void add_options(CLI::App& app, Options& o) {
  app.add_option("--robot", o.robot_args,
                 "robot file (YAML), FILE[@x,y,yaw_deg] for one robot on rise/<--id>/..., or repeated "
                 "ID=FILE[@x,y,yaw_deg] for several robots, each on rise/<ID>/... (start pose default: the world's "
                 "robot_start, then robot_starts)")
      ->capture_default_str();
  app.add_option("--world", o.world_file, "world file (YAML); default: the built-in yard");
  app.add_option("--id", o.id, "trainee/station id used in channel names (the plain --robot FILE form)")
      ->capture_default_str();
  app.add_option("--lcm", o.lcm_url, "LCM URL")->capture_default_str();
  app.add_flag("--fast", o.fast, "run as fast as possible instead of real-time paced");
  app.add_option("--duration", o.duration_s, "stop after S simulated seconds (0: run until SIGINT/SIGTERM)");
  app.add_option("--state-hz", o.state_hz, "RobotState rate")->capture_default_str()->check(CLI::Range(1.0, 1000.0));
  app.add_option("--panel-timeout-ms", o.panel_timeout_ms, "stop the robot when no PanelState arrives for this long")
      ->capture_default_str()
      ->check(CLI::Range(1, 10000));
  app.add_option("--instructor-key", o.instructor_key_file,
                 "instructor key file (hex, mode 0600; default env RISE_INSTRUCTOR_KEY): verifies signed "
                 "FaultCommand / TrainingControl; without it every such command is rejected")
      ->type_name("FILE");
  app.add_option("--command-window", o.command_window_s, "largest accepted |command time - now| (s)")
      ->capture_default_str();
  app.add_option("--log-level", o.log_level, "trace, debug, info, warn, error")->capture_default_str();
  app.add_flag("--allow-duplicate-id", o.allow_duplicate_id,
               "start even when another process already publishes a robot's rise/<id>/robot_state (by default "
               "that is refused: two simulators on one station mix their messages)");
  app.add_option("--scan-dir", o.scan_dir, "write the first robot's laser scan (scan_NNNN.pcd + .pose) here at start");
  app.add_option("--scan-every", o.scan_every_s, "and every S seconds of sim time (0: only at start)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--scan-format", o.scan_format, "PCD DATA: ascii or binary")
      ->capture_default_str()
      ->check(CLI::IsMember({"ascii", "binary"}));
}

// One station per --robot, with its robot file loaded. Throws naming the
// flag and what is wrong.
std::vector<std::unique_ptr<Station>> load_stations(const Options& o) {
  std::vector<std::unique_ptr<Station>> stations;
  std::vector<RobotArg> args;
  for (const auto& text : o.robot_args) args.push_back(parse_robot_arg(text));
  const bool plain = args.size() == 1 && args[0].id.empty();
  for (auto& a : args) {
    if (!plain && a.id.empty())
      throw std::invalid_argument("--robot " + a.file + ": with several robots each is ID=FILE[@x,y,yaw_deg]");
    auto st = std::make_unique<Station>();
    st->id = plain ? o.id : a.id;
    st->spec.description = rise::sim::load_robot_description(source_file(a.file));
    // The one-robot form keeps the robot file's name as the robot's id in messages and events.
    st->spec.id = plain ? st->spec.description.name : a.id;
    st->spec.start = a.start;
    for (const auto& other : stations)
      if (other->id == st->id) throw std::invalid_argument("--robot " + a.id + "=...: id given twice");
    stations.push_back(std::move(st));
  }
  return stations;
}

// The verifier of signed instructor commands, when a key is configured.
// False (after logging why) when the key cannot be read.
bool load_verifier(const Options& o, std::optional<rise::msgs::CommandVerifier>& verifier) {
  const std::string key_path = rise::msgs::instructor_key_path(o.instructor_key_file);
  if (key_path.empty()) {
    spdlog::info("no instructor key: fault and training commands are rejected");
    return true;
  }
  try {
    verifier.emplace(rise::msgs::load_instructor_key(key_path), static_cast<int64_t>(o.command_window_s * 1e6));
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return false;
  }
  spdlog::info("instructor commands verified with {}", key_path);
  return true;
}

std::vector<std::string> state_channels(const std::vector<std::unique_ptr<Station>>& stations) {
  std::vector<std::string> channels;
  for (const auto& st : stations) channels.push_back(rise::msgs::robot_state_channel(st->id));
  return channels;
}

// The running simulator: the world, each station's LCM side, and the
// commands it applies between steps.
class SimNode {
 public:
  SimNode(const Options& o, lcm::LCM& lcm, const rise_msgs::Publisher& self,
          std::vector<std::unique_ptr<Station>> stations, rise::sim::WorldDescription world,
          std::optional<rise::msgs::CommandVerifier> verifier)
      : o_(o), lcm_(lcm), self_(self), stations_(std::move(stations)), world_(std::move(world)),
        verifier_(std::move(verifier)),
        steps_per_state_(std::max(1, static_cast<int>(std::lround(1.0 / (o.state_hz * rise::sim::Simulation::kStepS))))),
        state_period_(std::chrono::microseconds(static_cast<int64_t>(std::lround(1e6 / o.state_hz)))),
        timeout_(std::chrono::milliseconds(o.panel_timeout_ms)),
        format_(o.scan_format == "ascii" ? rise::sim::PcdFormat::Ascii : rise::sim::PcdFormat::Binary) {}

  void subscribe();
  bool open_scanner();
  bool start();
  void log_ready() const;
  void run();
  void report() const;

 private:
  std::vector<rise::sim::RobotSpec> specs() const;
  void publish_states(bool feedback);
  void publish_feedback(const Station& st, const rise::sim::RobotSnapshot& snap, int64_t utime);
  void scan();
  void advance();
  void publish_events_and_cues();
  void handle_commands();
  void answer(std::size_t robot, const rise_msgs::SimControl& c, const std::string& kind, const std::string& what);
  void apply(std::size_t robot, const rise_msgs::SimControl& c);
  void tell(std::size_t robot, const std::string& kind, const std::string& a, const std::string& b,
            const std::string& detail);
  template <typename Command>
  bool admit(std::size_t robot, const Command& c, const std::string& channel);
  void apply_fault(std::size_t robot, const rise_msgs::FaultCommand& c);
  void apply_training(std::size_t robot, const rise_msgs::TrainingControl& c);

  const Options& o_;
  lcm::LCM& lcm_;
  const rise_msgs::Publisher self_;
  std::vector<std::unique_ptr<Station>> stations_;
  const rise::sim::WorldDescription world_;
  std::optional<rise::msgs::CommandVerifier> verifier_;
  // Reset rebuilds the whole world and robots: a Simulation is not assignable.
  std::optional<rise::sim::Simulation> sim_;
  std::vector<std::pair<std::size_t, rise_msgs::SimControl>> pending_control_;
  std::vector<std::pair<std::size_t, rise_msgs::FaultCommand>> pending_faults_;
  std::vector<std::pair<std::size_t, rise_msgs::TrainingControl>> pending_training_;

  std::optional<rise::sim::LaserScanner> scanner_;
  int scans_ = 0;
  double next_scan_s_ = 0.0;
  const int steps_per_state_;
  static constexpr int kStepsPerFeedback = 100;  // 10 Hz
  const std::chrono::microseconds state_period_;
  const std::chrono::milliseconds timeout_;
  const rise::sim::PcdFormat format_;
  std::chrono::steady_clock::time_point start_;
  int64_t step_ = 0;  // since start or the last reset
  // Real-time pacing restarts from here after a pause, step or reset.
  std::chrono::steady_clock::time_point paced_from_;
  int64_t paced_steps_ = 0;
  bool paused_ = false;
  std::chrono::steady_clock::time_point next_paused_state_;
  int64_t rejected_ = 0;
};

void SimNode::subscribe() {
  for (std::size_t i = 0; i < stations_.size(); ++i) {
    Station& st = *stations_[i];
    st.panel_channel = rise::msgs::panel_state_channel(st.id);
    st.state_channel = rise::msgs::robot_state_channel(st.id);
    st.feedback_channel = rise::msgs::panel_feedback_channel(st.id);
    st.event_channel = rise::msgs::sim_event_channel(st.id);
    st.control_channel = rise::msgs::sim_control_channel(st.id);
    st.sound_channel = rise::msgs::sound_channel(st.id);
    // Only the newest panel state matters to the physics; a short queue keeps
    // a stalled sim from acting on old sticks.
    rise::msgs::subscribe<&PanelListener::on>(lcm_, st.panel_channel, &st.panel)->setQueueCapacity(8);
    st.control.pending = &pending_control_;
    st.control.robot = i;
    rise::msgs::subscribe<&ControlListener::on>(lcm_, st.control_channel, &st.control)->setQueueCapacity(64);
    st.fault_channel = rise::msgs::fault_command_channel(st.id);
    st.training_channel = rise::msgs::training_control_channel(st.id);
    st.instructor.faults = &pending_faults_;
    st.instructor.training = &pending_training_;
    st.instructor.robot = i;
    rise::msgs::subscribe<&InstructorListener::on_fault>(lcm_, st.fault_channel, &st.instructor)->setQueueCapacity(64);
    rise::msgs::subscribe<&InstructorListener::on_training>(lcm_, st.training_channel, &st.instructor)->setQueueCapacity(64);
  }
}

// --scan-dir: the first robot's laser. False (after logging why) when it
// cannot scan.
bool SimNode::open_scanner() {
  if (o_.scan_dir.empty()) return true;
  const rise::sim::RobotDescription& first_robot = stations_.front()->spec.description;
  if (!first_robot.sensors.laser) {
    spdlog::error("--scan-dir: {} has no sensors.laser", first_robot.file);
    return false;
  }
  std::error_code ec;
  std::filesystem::create_directories(o_.scan_dir, ec);
  if (ec) {
    spdlog::error("--scan-dir {}: {}", o_.scan_dir, ec.message());
    return false;
  }
  scanner_.emplace(*first_robot.sensors.laser, first_robot.sensors.seed);
  return true;
}

std::vector<rise::sim::RobotSpec> SimNode::specs() const {
  std::vector<rise::sim::RobotSpec> out;
  for (const auto& st : stations_) out.push_back(st->spec);
  return out;
}

// Builds the world. False (after logging why) when it cannot.
bool SimNode::start() {
  try {
    sim_.emplace(specs(), world_);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return false;
  }
  return true;
}

void SimNode::log_ready() const {
  spdlog::info("rise-sim ready: world '{}', {} robot(s), {} on {}", world_.name, stations_.size(),
               o_.fast ? "as fast as possible" : "real time", o_.lcm_url);
  for (std::size_t i = 0; i < stations_.size(); ++i) {
    const Station& st = *stations_[i];
    const auto T = sim_->T_world_base(i);
    spdlog::info("robot '{}' ({}) at ({:.2f}, {:.2f}): {} → {}, {}, {}; control on {}", st.spec.id,
                 st.spec.description.file, T.translation().x(), T.translation().y(), st.panel_channel,
                 st.state_channel, st.event_channel, st.sound_channel, st.control_channel);
  }
}

// Every robot's RobotState and continuous sound cues; feedback too when asked.
void SimNode::publish_states(bool feedback) {
  for (std::size_t i = 0; i < stations_.size(); ++i) {
    Station& st = *stations_[i];
    const auto snap = sim_->snapshot(i);
    auto msg = to_message(snap, st.spec.id);
    msg.publisher = self_;
    add_objects(msg, *sim_, world_);
    lcm_.publish(st.state_channel, &msg);
    for (const auto& c : snap.sounds) {
      const auto cue = to_message(c);
      lcm_.publish(st.sound_channel, &cue);
    }
    if (snap.stop_reason != st.last_reason) {
      if (snap.motors_enabled) spdlog::info("{}: motors enabled", st.spec.id);
      else spdlog::info("{}: motors stopped: {}", st.spec.id, snap.stop_reason);
      st.last_reason = snap.stop_reason;
    }
    if (feedback) publish_feedback(st, snap, msg.utime);
  }
}

void SimNode::publish_feedback(const Station& st, const rise::sim::RobotSnapshot& snap, int64_t utime) {
  rise_msgs::PanelFeedback fb;
  fb.utime = utime;
  fb.panel_id = "";
  fb.num_leds = 0;  // the bridge owns power/fault/e-stop LEDs
  fb.display_names = {"speed"};
  fb.display_values = {static_cast<float>(snap.speed_mps())};
  fb.num_displays = 1;
  fb.buzzer = 0;
  fb.rumble = 0.0f;
  lcm_.publish(st.feedback_channel, &fb);
}

// Stop-and-go scanning: the whole scan at one instant of sim time.
void SimNode::scan() {
  char name[32];
  std::snprintf(name, sizeof name, "scan_%04d", scans_++);
  const auto stem = (std::filesystem::path(o_.scan_dir) / name).string();
  const auto scan = scanner_->scan(*sim_, 0);
  try {
    rise::sim::write_scan(stem, scan, format_);
    spdlog::info("scan {:.3f} s: {}.pcd, {} points", scan.time_s, stem, scan.points_sensor.size());
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
  }
  next_scan_s_ = o_.scan_every_s > 0 ? next_scan_s_ + o_.scan_every_s : std::numeric_limits<double>::infinity();
}

// One 1 ms step with everything that hangs on it: scans, events, sounds, states.
void SimNode::advance() {
  if (scanner_ && sim_->time_s() >= next_scan_s_ - 1e-9) scan();
  const auto now = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < stations_.size(); ++i) {
    const PanelListener& panel = stations_[i]->panel;
    rise::sim::ControlInput input = panel.input;
    input.fresh = panel.any && now - panel.received <= timeout_;
    sim_->set_input(i, input);
  }
  sim_->step();
  ++step_;
  publish_events_and_cues();
  if (step_ % steps_per_state_ == 0) publish_states(step_ % kStepsPerFeedback == 0);
}

void SimNode::publish_events_and_cues() {
  for (const auto& e : sim_->take_events()) {
    log_event(e);
    // To the robots it names; world events (doors, objects) to all.
    bool named = false;
    for (const auto& st : stations_) named = named || names_robot(e, st->spec.id);
    for (const auto& st : stations_) {
      if (named && stations_.size() > 1 && !names_robot(e, st->spec.id)) continue;
      const auto msg = to_message(e, st->spec.id);
      lcm_.publish(st->event_channel, &msg);
    }
  }
  for (const auto& c : sim_->take_sound_cues()) {
    const auto msg = to_message(c);
    lcm_.publish(stations_[sim_->robot_index(c.robot)]->sound_channel, &msg);
  }
}

void SimNode::answer(std::size_t robot, const rise_msgs::SimControl& c, const std::string& kind,
                     const std::string& what) {
  const std::string detail = "seq " + std::to_string(c.seq) + (what.empty() ? "" : ": " + what);
  spdlog::info("sim_control {:.3f} s: {} from '{}' on {} {}", sim_->time_s(), kind, c.issuer,
               stations_[robot]->control_channel, detail);
  tell(robot, kind, c.issuer, "", detail);
}

void SimNode::apply(std::size_t robot, const rise_msgs::SimControl& c) {
  if (c.command == "pause") {
    paused_ = true;
    next_paused_state_ = std::chrono::steady_clock::now();
    answer(robot, c, "sim_paused", "");
  } else if (c.command == "resume") {
    paused_ = false;
    answer(robot, c, "sim_resumed", "");
  } else if (c.command == "step" && c.steps >= 1 && c.steps <= kMaxControlSteps) {
    paused_ = true;
    for (int32_t i = 0; i < c.steps && !g_stop; ++i) advance();
    answer(robot, c, "sim_stepped", std::to_string(c.steps) + " steps of 1 ms");
    publish_states(false);
    next_paused_state_ = std::chrono::steady_clock::now() + state_period_;
  } else if (c.command == "reset") {
    sim_.emplace(specs(), world_);
    step_ = 0;
    next_scan_s_ = 0.0;
    for (auto& st : stations_) st->last_reason = "-";
    answer(robot, c, "sim_reset", "world and robots rebuilt, robots at their start poses");
    publish_states(false);
    next_paused_state_ = std::chrono::steady_clock::now() + state_period_;
  } else {
    answer(robot, c, "sim_control_refused",
           "command '" + c.command + "' with steps " + std::to_string(c.steps) + ": expected pause, resume, step " +
               "(steps 1.." + std::to_string(kMaxControlSteps) + ") or reset");
    return;
  }
  paced_from_ = std::chrono::steady_clock::now();
  paced_steps_ = 0;
}

// A SimEvent on the robot's sim_event channel.
void SimNode::tell(std::size_t robot, const std::string& kind, const std::string& a, const std::string& b,
                   const std::string& detail) {
  const Station& st = *stations_[robot];
  rise_msgs::SimEvent msg;
  msg.utime = rise::msgs::wall_us();
  msg.sim_time_s = sim_->time_s();
  msg.robot_id = st.spec.id;
  msg.kind = kind;
  msg.a = a;
  msg.b = b;
  msg.detail = detail;
  lcm_.publish(st.event_channel, &msg);
}

// Verifies one signed command: true to apply it; else it is reported as a
// command_rejected SimEvent (a = issuer, b = channel, detail = why, and
// the count so far) and logged.
template <typename Command>
bool SimNode::admit(std::size_t robot, const Command& c, const std::string& channel) {
  std::string why;
  if (!verifier_) why = "no instructor key on this station";
  else if (const auto v = verifier_->check(c, rise::msgs::wall_us()); v != rise::msgs::Verdict::Accepted) why = rise::msgs::to_string(v);
  else if (c.trainee_id != stations_[robot]->id) why = "meant for trainee '" + c.trainee_id + "'";
  if (why.empty()) return true;
  ++rejected_;
  spdlog::warn("rejected command on {} from '{}': {} ({} rejected so far)", channel, c.issuer, why, rejected_);
  tell(robot, "command_rejected", c.issuer, channel, why + " (" + std::to_string(rejected_) + " rejected)");
  return false;
}

void SimNode::apply_fault(std::size_t robot, const rise_msgs::FaultCommand& c) {
  const Station& st = *stations_[robot];
  if (!admit(robot, c, st.fault_channel)) return;
  if (c.action == "clear") {
    const std::size_t n = sim_->clear_fault(robot, c.fault_id);
    spdlog::info("fault clear '{}' from '{}': {} cleared", c.fault_id, c.issuer, n);
    return;  // a fault of the daemon's has the same id space: no refusal for an id not here
  }
  const auto kind = rise::sim::parse_sim_fault_kind(c.kind);
  // The daemon's kinds (input, wire, transport) come on the same channel: rise-hild applies them.
  static const std::set<std::string> daemon_kinds = {
      "stuck_at", "offset", "drift", "noise", "out_of_range", "intermittent", "disconnect", "can_drop",
      "can_delay", "can_corrupt", "can_bus_off", "modbus_exception", "modbus_timeout", "lcm_loss", "lcm_latency"};
  if (!kind && daemon_kinds.count(c.kind) && c.action == "inject") {
    spdlog::debug("fault '{}' ({}) is rise-hild's", c.fault_id, c.kind);
    return;
  }
  std::string error;
  if (c.action != "inject") error = "action '" + c.action + "': expected inject or clear";
  else if (!kind) error = "'" + c.kind + "' is not a sim fault";
  else {
    rise::sim::PhysicsFault f;
    f.id = c.fault_id;
    f.kind = *kind;
    f.target = c.target;
    f.value = c.value;
    f.seed = static_cast<uint64_t>(c.seed);
    f.duration_s = c.duration_s;
    error = sim_->set_fault(robot, f);
  }
  if (!error.empty()) {
    spdlog::warn("fault '{}' from '{}' refused: {}", c.fault_id, c.issuer, error);
    tell(robot, "fault_refused", c.issuer, c.fault_id, error);
  }
}

void SimNode::apply_training(std::size_t robot, const rise_msgs::TrainingControl& c) {
  const Station& st = *stations_[robot];
  if (!admit(robot, c, st.training_channel)) return;
  rise_msgs::SimControl sc{};
  sc.issuer = c.issuer;
  sc.steps = 0;
  if (c.command == "start") sc.command = "resume";
  else if (c.command == "stop") sc.command = "pause";
  else if (c.command == "restart") sc.command = "reset";
  else {
    tell(robot, "command_rejected", c.issuer, st.training_channel, "command '" + c.command + "': expected start, stop or restart");
    return;
  }
  apply(robot, sc);
  if (c.command == "restart") paused_ = false;
  tell(robot, c.command == "start" ? "training_started" : c.command == "stop" ? "training_stopped" : "training_restarted",
       c.issuer, c.task, "task " + (c.task.empty() ? std::string("-") : c.task));
}

// The commands that came in since the last step, in arrival order per kind.
void SimNode::handle_commands() {
  for (const auto& [robot, c] : pending_control_) apply(robot, c);
  pending_control_.clear();
  for (const auto& [robot, c] : pending_faults_) apply_fault(robot, c);
  pending_faults_.clear();
  for (const auto& [robot, c] : pending_training_) apply_training(robot, c);
  pending_training_.clear();
}

// Until SIGINT/SIGTERM or --duration of sim time.
void SimNode::run() {
  start_ = std::chrono::steady_clock::now();
  paced_from_ = start_;
  next_paused_state_ = start_;
  while (!g_stop && (o_.duration_s <= 0 || sim_->time_s() < o_.duration_s)) {
    // Take every waiting LCM message without blocking the physics.
    pollfd pfd{lcm_.getFileno(), POLLIN, 0};
    while (::poll(&pfd, 1, 0) > 0) lcm_.handle();
    handle_commands();

    if (paused_) {
      // No stepping; RobotState still goes out, with the same sim time.
      if (std::chrono::steady_clock::now() >= next_paused_state_) {
        publish_states(false);
        next_paused_state_ += state_period_;
      }
      ::poll(&pfd, 1, 1);
      continue;
    }
    advance();
    ++paced_steps_;
    if (!o_.fast) std::this_thread::sleep_until(paced_from_ + std::chrono::microseconds(paced_steps_ * 1000));
  }
}

void SimNode::report() const {
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  int64_t panel_states = 0;
  for (const auto& st : stations_) panel_states += st->panel.count;
  spdlog::info("rise-sim stopped: {:.1f} s simulated in {:.1f} s ({:.1f}x real time), {} robot(s), {} panel states, "
               "{} malformed LCM messages dropped",
               sim_->time_s(), wall_s, wall_s > 0 ? sim_->time_s() / wall_s : 0.0, stations_.size(), panel_states,
               rise::msgs::malformed_messages().load());
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rise-sim: ODE robot simulator driven by PanelState over LCM"};
  Options o;
  add_options(app, o);
  if (const auto code = rise::cli::parse_command_line(app, "rise-sim", argc, argv)) return *code;
  spdlog::set_level(spdlog::level::from_str(o.log_level));

  std::vector<std::unique_ptr<Station>> stations;
  rise::sim::WorldDescription world = rise::sim::default_world();
  try {
    stations = load_stations(o);
    if (!o.world_file.empty()) world = rise::sim::load_world_description(source_file(o.world_file));
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  std::optional<rise::msgs::CommandVerifier> verifier;
  if (!load_verifier(o, verifier)) return 2;
  lcm::LCM lcm(o.lcm_url);
  if (!lcm.good()) {
    spdlog::error("cannot open LCM at {}", o.lcm_url);
    return 2;
  }
  // One publisher per station: listen before the first message.
  const rise_msgs::Publisher self = rise::msgs::init_publisher("rise-sim");
  const std::vector<std::string> channels = state_channels(stations);
  if (!o.allow_duplicate_id)
    if (const auto other = rise::msgs::probe_channels<rise_msgs::RobotState>(lcm, channels, rise::msgs::kProbeMs)) {
      spdlog::error("{} is already published by {}: refusing to start a second simulator for it (give another "
                    "--id, or --allow-duplicate-id)",
                    other->channel, rise::msgs::describe(other->publisher, rise::msgs::wall_us()));
      return 2;
    }
  // Another process publishing a robot's state: reported once by each side;
  // of two that started together, the later one gives way.
  int exit_code = 0;
  rise::msgs::PublisherListener<rise_msgs::RobotState> others(
      self.session_id, [&](const rise::msgs::PublisherWatch::Other& other) {
        spdlog::warn("another publisher on {}: {}", other.channel, rise::msgs::describe(other.publisher, rise::msgs::wall_us()));
        if (o.allow_duplicate_id || !rise::msgs::gives_way(self, other.publisher, rise::msgs::wall_us())) return;
        spdlog::error("{} started first: this rise-sim stops (give another --id, or --allow-duplicate-id)",
                      other.publisher.program);
        exit_code = 2;
        g_stop = 1;
      });
  for (const std::string& channel : channels) others.listen(lcm, channel);
  rise::msgs::ClockEchoResponder clock_echo(lcm, self);  // the instructor measures this host's clock offset
  for (const auto& st : stations) clock_echo.listen(st->id);

  SimNode node(o, lcm, self, std::move(stations), std::move(world), std::move(verifier));
  node.subscribe();
  if (!node.open_scanner() || !node.start()) return 2;
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  node.log_ready();
  node.run();
  node.report();
  return exit_code;
}
