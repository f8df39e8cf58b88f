// The pages in headless Chromium (Debian's chromium, driven by playwright-core
// from instructor/web) against `rise-instructor serve` and `rise-sim` as
// separate processes over LCM: the console shows the robot moving while the
// console emulator drives it through rise-hild, and its fault button injects
// a signed fault that rise-hild applies and reports in PanelState, and its
// camera-blackout button blacks out the camera inset until the fault ends; the
// virtual panel page drives the robot, and closing it stops the robot; the
// trainee page's camera follows the robot, its HUD shows the failsafe, its
// WebAudio plays SoundCues at their gain; `rise demo --view` serves it; the
// Training Builder edits a copy of the shipped training by clicks and typing,
// and the saved file walks differently in `rise-trainer check --walk`.

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <thread>

#include "msgs/channels.hpp"
#include "msgs/clock.hpp"
#include "msgs/command_auth.hpp"
#include "process/child_process.hpp"
#include "rise_msgs/PanelFeedback.hpp"
#include "rise_msgs/SimEvent.hpp"
#include "rise_msgs/SoundCue.hpp"
#include "rise_msgs/TaskEvent.hpp"
#include "rise_msgs/TaskStatus.hpp"
#include "browser_support.hpp"
#include "web_peer.hpp"

namespace fs = std::filesystem;
using namespace rise::instructor_test;
using rise::process::ChildProcess;

namespace {
/// rise-sim and rise-instructor serve for one trainee, in a scratch folder.
struct Stations {
  std::string id = "web" + std::to_string(::getpid());
  std::string token = "browser-" + std::to_string(::getpid());
  fs::path dir;
  int port = free_port();
  ChildProcess sim, server, hild, emulator;

  /// `emulated`: the console emulator → rise-hild drive the robot too.
  /// `world`: a file of sim/worlds for rise-sim and the server ("": the yard).
  explicit Stations(bool emulated, const std::string& world = "") {
    char tmpl[] = "/tmp/rise-browser-test-XXXXXX";
    dir = ::mkdtemp(tmpl);
    rise::msgs::write_new_instructor_key((dir / "instructor.key").string());
    const std::string key = (dir / "instructor.key").string();
    fs::create_directories(dir / "reports" / id);
    std::ofstream(dir / "reports" / id / "training.html") << "<html><body>training report</body></html>";
    fs::create_directories(dir / "scenarios");
    std::ofstream(dir / "scenarios" / "stuck.yaml")
        << "scenario: stuck\nfaults:\n  - {id: s, kind: stuck_at, target: drive_y, value: 0.4, at: 1.0}\n";
    std::vector<std::string> sim_argv{kBin + "/rise-sim", "--id", id, "--lcm", kLcm, "--panel-timeout-ms", "100",
                                      "--instructor-key", key};
    if (!world.empty()) sim_argv.insert(sim_argv.end(), {"--world", kSource + "/sim/worlds/" + world});
    sim = ChildProcess(sim_argv, (dir / "sim.log").string());
    if (emulated) {
      // Forward at half stick, dead-man held, for as long as the test runs.
      std::ofstream(dir / "drive.txt") << "0.0 mode drive\n0.0 speed medium\n0.2 deadman pressed\n0.5 drive_y 0.5\n";
      const std::string bus = "127.0.0.1:" + std::to_string(free_port()) + "/can0";
      const std::string panel = kSource + "/panels/definitions/rise_console.yaml";
      emulator = ChildProcess({kBin + "/rise-panel", "emulate", "--panel", panel, "--can", "socketcand+listen://" + bus,
                               "--script", (dir / "drive.txt").string(), "--hold"},
                              (dir / "emulator.log").string());
      hild = ChildProcess({kBin + "/rise-hild", "--panel", panel, "--can", "socketcand://" + bus, "--id", id, "--lcm",
                           kLcm, "--instructor-key", key},
                          (dir / "hild.log").string());
    }
    server = ChildProcess({kBin + "/rise-instructor", "serve", "--listen", "127.0.0.1:" + std::to_string(port), "--token",
                           token, "--lcm", kLcm, "--world", kSource + "/sim/worlds/" + (world.empty() ? "yard.yaml" : world), "--instructor-key",
                           (dir / "instructor.key").string(), "--reports-dir", (dir / "reports").string(), "--scenarios-dir",
                           (dir / "scenarios").string()},
                          (dir / "server.log").string());
  }
  ~Stations() {
    server.stop();
    hild.stop();
    emulator.stop();
    sim.stop();
    fs::remove_all(dir);
  }
  /// Waits for the server to answer with the token and the sim to publish.
  bool ready(TraineePeer& peer) {
    httplib::Client http("127.0.0.1", port);
    http.set_connection_timeout(0, 200'000);
    bool up = false;
    return peer.wait_until(
        [&] { return up && !peer.robot.empty(); }, 20000, [&] {
          if (!up) {
            auto r = http.Get("/api/world", {{"X-Rise-Token", token}});
            up = r && r->status == 200;
          }
        });
  }
  std::string base() const { return "http://127.0.0.1:" + std::to_string(port); }
  std::string out_dir() const { return screens_dir(); }
};

}  // namespace

TEST_CASE("the console shows the robot moving while the emulator drives, and a click injects a fault", "[instructor]") {
  if (const auto why = missing_browser(); !why.empty()) {
    WARN("skipped: " << why);
    return;
  }
  Stations st(true);
  TraineePeer peer(st.id);
  REQUIRE(peer.good());
  REQUIRE(st.ready(peer));
  ChildProcess node({"/usr/bin/node", kSource + "/tests/instructor/browser/console_check.cjs", st.base(), st.token, st.id,
                     st.out_dir(), kWeb},
                    (st.dir / "console_check.log").string());
  // The emulated console drives while the page watches; a trainer's TaskStatus at ~2 Hz.
  rise_msgs::TaskStatus task{};
  task.trainee_id = st.id;
  task.training = "drill";
  task.task = "approach_object";
  task.state = "running";
  task.score = 7;
  int ticks = 0;
  const bool finished = peer.wait_until([&] { return !node.running(); }, 120000, [&] {
    if (ticks++ % 50 == 0) peer.lcm().publish(rise::msgs::task_status_channel(st.id), &task);
  });
  if (!finished) node.stop();
  const auto result = read_result((st.dir / "console_check.log").string());
  INFO(read_file((st.dir / "console_check.log").string()));
  REQUIRE(finished);
  REQUIRE(result.isObject());
  REQUIRE_FALSE(result.isMember("error"));
  CHECK(result["no_token_status"].asInt() == 401);
  CHECK(result["wrong_token_status"].asInt() == 401);
  CHECK(result["status"].asInt() == 200);
  const double dx = result["later"][0].asDouble() - result["first"][0].asDouble();
  const double dy = result["later"][1].asDouble() - result["first"][1].asDouble();
  CHECK(std::hypot(dx, dy) > 0.5);
  // The page was pushed to over one second (the rate is a figure, not asserted:
  // no timed assertions; the server refuses a push rate under 20 Hz).
  WARN("console page: " << result["pushes_per_s"].asInt() << " pushes in 1 s (--push-hz 50)");
  CHECK(result["push_continued"].asBool());
  const auto& stats = result["stats"];
  CHECK(stats["map"]["variance"].asDouble() > 50.0);
  CHECK(stats["map"]["robot_pixels"].asInt() > 20);
  CHECK(stats["view3d"]["variance"].asDouble() > 50.0);
  CHECK(stats["view3d"]["robot_pixels"].asInt() > 200);
  CHECK(is_png(st.out_dir() + "/instructor_console.png"));
  CHECK(is_png(st.out_dir() + "/instructor_view3d.png"));
  CHECK(result["page_errors"].size() == 0);
  CHECK(result["scenario_options"].asInt() == 1);
  CHECK(result["training_text"].asString().find("approach_object") != std::string::npos);
  CHECK(result["report_link"].asString() == "/reports/" + st.id + "/training.html");
  CHECK(result["report_status"].asInt() == 200);
  CHECK(result["report_body"].asString().find("training report") != std::string::npos);
  // The click published one signed FaultCommand for this trainee.
  CHECK(result["fault_result"].asString().find("published") != std::string::npos);
  REQUIRE(peer.wait_until([&] { return !peer.faults.empty(); }, 5000));
  CHECK(peer.faults[0].kind == "stuck_at");
  CHECK(peer.faults[0].trainee_id == st.id);
  rise::msgs::CommandVerifier verifier(rise::msgs::load_instructor_key((st.dir / "instructor.key").string()));
  // Checked as of its own time: the page ran on for the camera blackout's 10 s,
  // past the 5 s window (the window itself is signed_command_test's).
  CHECK(verifier.check(peer.faults[0], peer.faults[0].utime) == rise::msgs::Verdict::Accepted);
  // rise-hild took it: the fault is in PanelState.active_faults over LCM, and on the page.
  const auto has_fault = [](const rise_msgs::PanelState& p) {
    return std::any_of(p.active_faults.begin(), p.active_faults.end(),
                       [](const std::string& f) { return f.rfind("stick-stuck: stuck_at drive_y", 0) == 0; });
  };
  CHECK(std::any_of(peer.daemon_panels.begin(), peer.daemon_panels.end(), has_fault));
  CHECK(result["page_faults"].asString().find("stick-stuck: stuck_at drive_y") != std::string::npos);
  // The camera-blackout button: rise-sim listed it in RobotState, the inset
  // was the camera's picture, then black with its label, then the picture again.
  bool listed = false;
  for (const auto& f : result["blackout_robot_faults"])
    listed |= f.asString().rfind("camera-blackout: camera_blackout", 0) == 0;
  CHECK(listed);
  REQUIRE(peer.faults.size() >= 2);
  CHECK(peer.faults[1].kind == "camera_blackout");
  CHECK(verifier.check(peer.faults[1], peer.faults[1].utime) == rise::msgs::Verdict::Accepted);
  CHECK(result["inset_before"]["mean"].asDouble() > 20.0);
  CHECK(result["inset_before"]["label"].asString().empty());
  CHECK(result["inset_blackout"]["max"].asDouble() < 8.0);
  CHECK(result["inset_blackout"]["label"].asString().find("camera blackout") != std::string::npos);
  CHECK(result["inset_after"]["mean"].asDouble() > 20.0);
  CHECK(result["inset_after"]["label"].asString().empty());
  CHECK(is_png(st.out_dir() + "/instructor_view3d_blackout.png"));
}

namespace {
/// The drive stick's dot where the page says it drew it, and there in the
/// canvas's pixels: at rest in the middle, W pushes it 75 px up.
void check_stick(const Json::Value& s, double x, double y) {
  INFO(text(s));
  CHECK(s["page"]["x"].asDouble() == x);
  CHECK(s["page"]["y"].asDouble() == y);
  CHECK(s["pixels"].asInt() > 300);  // the dot: r 14 px
  CHECK(std::abs(s["cx"].asDouble() - (90.0 + 75.0 * x)) < 1.5);
  CHECK(std::abs(s["cy"].asDouble() - (90.0 - 75.0 * y)) < 1.5);
  CHECK(std::abs(s["cy"].asDouble() - s["page"]["py"].asDouble()) < 1.5);
}

/// "rgb(r, g, b)" → distance to another such colour.
double colour_distance(const std::string& a, const std::string& b) {
  int r1 = 0, g1 = 0, b1 = 0, r2 = 0, g2 = 0, b2 = 0;
  std::sscanf(a.c_str(), "rgb(%d, %d, %d)", &r1, &g1, &b1);
  std::sscanf(b.c_str(), "rgb(%d, %d, %d)", &r2, &g2, &b2);
  return std::hypot(r1 - r2, g1 - g2, b1 - b2);
}

void check_keyboard_widgets(const Json::Value& r) {
  check_stick(r["stick_rest"], 0, 0);
  check_stick(r["stick_w"], 0, 1);
  check_stick(r["stick_released"], 0, 0);
  // Space: the dead-man button and line show it held, in a colour of their own.
  CHECK(r["idle"]["deadman_held"].asString() == "released");
  CHECK(r["space"]["deadman_held"].asString() == "held");
  CHECK(r["space"]["deadman_text"].asString() == "DEAD-MAN HELD");
  CHECK(colour_distance(r["idle"]["deadman_colour"].asString(), r["space"]["deadman_colour"].asString()) > 80);
  // Esc: latched is a striped button and a banner; the server's PanelState is failsafe.
  CHECK_FALSE(r["idle"]["banner_visible"].asBool());
  CHECK(r["idle"]["estop_image"].asString() == "none");
  CHECK(r["estop"]["banner_visible"].asBool());
  CHECK(r["estop"]["banner_text"].asString().find("E-STOP LATCHED") != std::string::npos);
  CHECK(r["estop"]["estop_button"].asString() == "held");
  CHECK(r["estop"]["estop_image"].asString().find("repeating-linear-gradient") != std::string::npos);
  CHECK(r["estop_panel"]["failsafe"].asBool());
  CHECK_FALSE(r["estop_released"]["banner_visible"].asBool());
  CHECK(r["estop_released"]["estop_button"].asString() == "released");
  // 3, 1, 2: the speed widget and what is sent, and the server's PanelState after.
  const char* speeds[] = {"fast", "slow", "medium"};
  for (int i = 0; i < 3; ++i) {
    const auto& w = r["speeds"][i];
    CHECK(w["speed_value"].asString() == speeds[i]);
    CHECK(w["sent_speed"].asString() == speeds[i]);
    REQUIRE(w["speed_on"].size() == 1);
    CHECK(w["speed_on"][0].asString() == speeds[i]);
  }
  CHECK(r["speed_panel"].asString() == "medium");
  // The mouse at 3/4 of the arm stick's width: x 0.5, the dot 37.5 px right of the middle.
  CHECK(r["arm_mouse"]["x"].asDouble() == Approx(0.5).margin(0.03));
  CHECK(r["arm_mouse"]["y"].asDouble() == Approx(0.0).margin(0.03));
  CHECK(r["arm_mouse"]["px"].asDouble() == Approx(127.5).margin(2.5));
  // Driving and the gamepad: the widgets show it too.
  CHECK(r["driving"]["deadman_held"].asString() == "held");
  CHECK(r["stick_driving"]["page"]["y"].asDouble() == 1.0);
  CHECK(r["gamepad_widgets"]["deadman_held"].asString() == "held");
  CHECK(r["gamepad_stick"]["page"]["y"].asDouble() == 1.0);
  CHECK(r["gamepad_stick"]["cy"].asDouble() < 20.0);
}

/// The PanelFeedback the test published shows on the page; rise-sim's speed
/// display shows the robot moving.
void check_feedback(const Json::Value& r) {
  const auto& f = r["feedback"];
  INFO(text(f));
  CHECK(f["leds"]["power"].asBool());
  CHECK_FALSE(f["leds"]["fault"].asBool());
  CHECK(f["leds"]["estop"].asBool());
  CHECK(f["leds"]["door_open"].asBool());  // not in the definition: shown as well
  CHECK(f["displays"]["speed"].asString() == "0.75");
  CHECK(f["displays"]["battery"].asString() == "87.50");
  CHECK(f["buzzer"].asString() == "buzzer beep");
  CHECK(colour_distance(f["lit_colour"].asString(), "rgb(51, 51, 51)") > 80);
  CHECK(std::stod(r["sim_speed_display"].asString()) > 0.05);
}
}  // namespace

TEST_CASE("the virtual panel page drives the robot from keyboard and gamepad, and closing it stops the robot", "[instructor]") {
  if (const auto why = missing_browser(); !why.empty()) {
    WARN("skipped: " << why);
    return;
  }
  Stations st(false);
  TraineePeer peer(st.id);
  REQUIRE(peer.good());
  REQUIRE(st.ready(peer));
  const auto start = peer.robot.back();
  // The feedback a console would show, for a trainee of its own (rise-sim's
  // 10 Hz feedback for st.id names no LEDs and would replace these).
  const std::string fb_id = st.id + "fb";
  ChildProcess node({"/usr/bin/node", kSource + "/tests/instructor/browser/panel_check.cjs", st.base(), st.token, st.id,
                     st.out_dir(), kWeb, fb_id},
                    (st.dir / "panel_check.log").string());
  rise_msgs::PanelFeedback fb{};
  fb.led_names = {"power", "fault", "estop", "door_open"};
  fb.led_on = {1, 0, 1, 1};
  fb.num_leds = 4;
  fb.display_names = {"speed", "battery"};
  fb.display_values = {0.75f, 87.5f};
  fb.num_displays = 2;
  fb.buzzer = 2;
  fb.rumble = 0.0f;
  int ticks = 0;
  const bool finished = peer.wait_until([&] { return !node.running(); }, 90000, [&] {
    if (ticks++ % 10 != 0) return;
    fb.utime = rise::msgs::wall_us();
    peer.lcm().publish(rise::msgs::panel_feedback_channel(fb_id), &fb);
  });
  if (!finished) node.stop();
  const auto result = read_result((st.dir / "panel_check.log").string());
  INFO(read_file((st.dir / "panel_check.log").string()));
  REQUIRE(finished);
  REQUIRE(result.isObject());
  REQUIRE_FALSE(result.isMember("error"));
  CHECK(result["status"].asInt() == 200);
  CHECK(result["sticks"].asInt() == 2);
  CHECK(result["buttons"].asInt() >= 4);
  CHECK(result["closed"].asBool());
  CHECK(result["page_errors"].size() == 0);
  check_keyboard_widgets(result);
  check_feedback(result);
  // The keys released the dead-man; the gamepad held it and drove forward.
  CHECK_FALSE(result["released"].asBool());
  CHECK(result["gamepad_panel"]["deadman"].asBool());
  CHECK(result["gamepad_panel"]["axes"]["drive_y"].asDouble() > 0.9);
  CHECK(result["gamepad_label"].asString() == "1 gamepad(s)");
  // The page's PanelState drove rise-sim: the robot moved on LCM.
  double moved = 0.0;
  for (const auto& r : peer.robot) moved = std::max(moved, distance_xy(r, start));
  CHECK(moved > 0.5);
  bool drove = false;
  for (const auto& p : peer.panels) drove |= !p.failsafe && p.deadman && p.axes[1].value > 0.9f;
  CHECK(drove);
  // Closed with the keys held: the server publishes the safe state, the robot stops.
  const std::size_t at_close = peer.panels.size();
  REQUIRE(peer.wait_until([&] { return peer.panels.size() > at_close && peer.panels.back().failsafe; }, 5000));
  const auto& safe = peer.panels.back();
  CHECK_FALSE(safe.deadman);
  for (const auto& a : safe.axes) CHECK(a.value == 0.0f);
  CHECK((safe.sources[0].stale || !safe.sources[0].connected));
  REQUIRE(peer.wait_until(
      [&] {
        const auto& r = peer.robot.back();
        return !r.motors_enabled && std::abs(r.linear_velocity_mps[0]) < 0.02;
      },
      5000));
}

namespace {
/// Whether the check's log has a line `line` yet (the check says where it is).
bool log_has(const fs::path& log, const std::string& line) {
  std::ifstream in(log);
  for (std::string l; std::getline(in, l);)
    if (l == line) return true;
  return false;
}

/// The utime of the first PanelState of the failsafe run that holds the one
/// of `utime` (the one the page showed), or 0 when none has that utime.
int64_t failsafe_run_start(const std::vector<rise_msgs::PanelState>& panels, int64_t utime) {
  for (std::size_t i = 0; i < panels.size(); ++i) {
    if (panels[i].utime != utime) continue;
    while (i > 0 && panels[i - 1].failsafe) --i;
    return panels[i].utime;
  }
  return 0;
}

/// The HUD's change to FAILSAFE (the page's log entry) against the first
/// failsafe PanelState on LCM: publication → the text in the DOM, in ms.
/// Both clocks are this host's wall clock.
double hud_latency_ms(const Json::Value& entry, int64_t first_utime) {
  return entry["dom_ms"].asDouble() - static_cast<double>(first_utime) / 1000.0;
}

rise_msgs::SoundCue probe_cue(const std::string& id, bool continuous, const std::string& sample, float gain) {
  rise_msgs::SoundCue c{};
  c.utime = rise::msgs::wall_us();
  c.robot_id = id;
  c.name = continuous ? "probe" : "probe_horn";
  c.sample = sample;
  c.continuous = continuous;
  c.gain = gain;
  c.pitch = 1.0f;
  c.detail = "browser_test";
  return c;
}
}  // namespace

TEST_CASE("the trainee page's camera follows the robot, its HUD shows the task and the failsafe within 200 ms",
          "[instructor]") {
  if (const auto why = missing_browser(); !why.empty()) {
    WARN("skipped: " << why);
    return;
  }
  Stations st(true, "building.yaml");  // room A, the door to room B straight ahead
  TraineePeer peer(st.id);
  REQUIRE(peer.good());
  REQUIRE(st.ready(peer));
  const fs::path log = st.dir / "trainee_check.log";
  ChildProcess node({"/usr/bin/node", kSource + "/tests/instructor/browser/trainee_check.cjs", st.base(), st.token, st.id,
                     st.out_dir(), kWeb, "drive"},
                    log.string());
  // A trainer's TaskStatus and a TaskEvent at ~2 Hz while the emulator drives.
  rise_msgs::TaskStatus task{};
  task.trainee_id = st.id;
  task.task = "approach_object";
  task.state = "running";
  task.time_limit_s = 120.0;
  rise_msgs::TaskEvent event{};
  event.task = "approach_object";
  event.name = "object_touched";
  event.points = 5;
  event.score = 5;
  int ticks = 0;
  int64_t stopped_us = 0;
  const bool finished = peer.wait_until([&] { return !node.running(); }, 90000, [&] {
    if (ticks++ % 50 == 0) {
      task.utime = event.utime = rise::msgs::wall_us();
      task.task_time_s = ticks * 0.01;
      peer.lcm().publish(rise::msgs::task_status_channel(st.id), &task);
      peer.lcm().publish(rise::msgs::task_event_channel(st.id), &event);
    }
    // The page is ready: the console goes away, rise-hild fails safe.
    if (stopped_us == 0 && ticks % 5 == 0 && log_has(log, "READY failsafe")) {
      stopped_us = rise::msgs::wall_us();
      st.emulator.stop();
    }
  });
  if (!finished) node.stop();
  const auto result = read_result(log.string());
  INFO(read_file(log.string()));
  REQUIRE(finished);
  REQUIRE(result.isObject());
  REQUIRE_FALSE(result.isMember("error"));
  CHECK(result["status"].asInt() == 200);
  CHECK(result["page_errors"].size() == 0);
  // The camera moved with the robot, stays at its mount (skid4's front camera,
  // 0.41 m ahead), and the picture changed.
  const auto moved = [](const Json::Value& a, const Json::Value& b) {
    return std::hypot(a[0].asDouble() - b[0].asDouble(), a[1].asDouble() - b[1].asDouble());
  };
  CHECK(moved(result["camera_first"]["position"], result["camera_later"]["position"]) > 0.5);
  CHECK(moved(result["robot_first"], result["robot_later"]) > 0.4);
  CHECK(moved(result["camera_later"]["position"], result["robot_later"]) < 1.0);
  CHECK(result["thumb_changed"].asDouble() > 0.05);
  CHECK(result["stats"]["variance"].asDouble() > 50.0);
  WARN("trainee page: camera moved " << moved(result["camera_first"]["position"], result["camera_later"]["position"])
                                     << " m; " << result["thumb_changed"].asDouble() * 100
                                     << " % of the picture's 32 × 18 cells changed by more than 8 grey levels");
  // The HUD: speed, the panel, the task with its time left and its event.
  CHECK(result["hud"]["hud-panel"].asString() == "OK · dead-man held");
  CHECK(std::stod(result["hud"]["hud-speed"].asString()) > 0.05);
  CHECK(result["hud"]["hud-time"].asString().find("s left") != std::string::npos);
  CHECK(result["hud"]["hud-events"].asString().find("object_touched +5") != std::string::npos);
  CHECK(result["wheel_cue"]["gain"].asDouble() > 0.0);  // rise-sim's motor cue came through the stream
  CHECK(result["shown_before"]["pip"].asBool());
  CHECK(result["shown_before"]["minimap"].asBool());
  CHECK_FALSE(result["shown_off"]["pip"].asBool());
  CHECK_FALSE(result["shown_off"]["minimap"].asBool());
  CHECK(result["shown_on"]["pip"].asBool());
  CHECK(result["shown_on"]["minimap"].asBool());
  // The door the robot pushed open, drawn swung the way it drives, into
  // room B (a turn of -80° from closed), whether the page heard of it as it
  // happened or from the stream's recent events.
  CHECK(result["door_after"].asDouble() == Approx(-80.0 * M_PI / 180.0));
  CHECK(is_png(st.out_dir() + "/trainee_page.png"));
  // The failsafe: rise-hild's first failsafe PanelState after the console
  // went away, to the HUD's text in the page's DOM.
  REQUIRE(stopped_us > 0);
  const int64_t first = failsafe_run_start(peer.daemon_panels, result["failsafe"]["panel_utime"].asInt64());
  REQUIRE(first > 0);
  const auto& e = result["failsafe"];
  CHECK(result["failsafe_text"].asString().rfind("FAILSAFE", 0) == 0);
  const double latency = hud_latency_ms(e, first);
  WARN("HUD failsafe: PanelState published → DOM " << latency << " ms (push arrival → DOM "
                                                    << e["dom_ms"].asDouble() - e["arrival_ms"].asDouble()
                                                    << " ms, → next frame "
                                                    << e["frame_ms"].asDouble() - e["dom_ms"].asDouble() << " ms more); console stopped → DOM "
                                                    << e["dom_ms"].asDouble() - static_cast<double>(stopped_us) / 1000.0 << " ms");
  CHECK(latency >= 0.0);
  CHECK(latency < 200.0);
}

TEST_CASE("the trainee page plays SoundCues at their gain, and shows the virtual panel failing safe", "[instructor]") {
  if (const auto why = missing_browser(); !why.empty()) {
    WARN("skipped: " << why);
    return;
  }
  Stations st(false);
  TraineePeer peer(st.id);
  REQUIRE(peer.good());
  REQUIRE(st.ready(peer));
  const fs::path log = st.dir / "trainee_check.log";
  ChildProcess node({"/usr/bin/node", kSource + "/tests/instructor/browser/trainee_check.cjs", st.base(), st.token, st.id,
                     st.out_dir(), kWeb, "sound"},
                    log.string());
  // A continuous cue at the gain of the phase the page asks for, every 20 ms
  // as rise-sim sends its own; one horn one-shot when asked.
  const float gains[] = {0.2f, 0.4f, 0.8f, 0.0f};
  int phase = -1, ticks = 0;
  bool horn = false;
  const bool finished = peer.wait_until([&] { return !node.running(); }, 90000, [&] {
    if (++ticks % 2 != 0) return;
    if (phase < 3 && log_has(log, "PHASE " + std::to_string(phase + 1))) ++phase;
    if (phase >= 0) {
      const auto cue = probe_cue(st.id, true, "wheel_motor_whine", gains[phase]);
      peer.lcm().publish(rise::msgs::sound_channel(st.id), &cue);
    }
    if (!horn && log_has(log, "ONESHOT")) {
      horn = true;
      const auto cue = probe_cue(st.id, false, "horn", 0.8f);
      peer.lcm().publish(rise::msgs::sound_channel(st.id), &cue);
    }
  });
  if (!finished) node.stop();
  const auto result = read_result(log.string());
  INFO(read_file(log.string()));
  REQUIRE(finished);
  REQUIRE(result.isObject());
  REQUIRE_FALSE(result.isMember("error"));
  CHECK(result["page_errors"].size() == 0);
  CHECK(result["button_before"].asString().find("click to enable sound") != std::string::npos);
  CHECK(result["button_after"].asString().find("sound on") != std::string::npos);
  // The level follows the gain, roughly in proportion, and is silent at 0.
  const auto& lv = result["levels"];
  REQUIRE(lv.size() == 4);
  const double r2 = lv[0]["rms"].asDouble(), r4 = lv[1]["rms"].asDouble(), r8 = lv[2]["rms"].asDouble(),
               r0 = lv[3]["rms"].asDouble();
  WARN("trainee page audio RMS at gain 0.2 / 0.4 / 0.8 / 0: " << r2 << " / " << r4 << " / " << r8 << " / " << r0
                                                              << "; horn " << result["one_shot_rms"].asDouble());
  CHECK(r2 > 0.005);
  CHECK(r4 / r2 == Approx(2.0).epsilon(0.2));
  CHECK(r8 / r2 == Approx(4.0).epsilon(0.2));
  CHECK(r0 < 0.01 * r8);
  CHECK(result["held"]["probe"]["voice"].asString() == "wheel_motor_whine");
  // The one-shot sounded and died away.
  CHECK(result["one_shot_rms"].asDouble() > 0.01);
  CHECK(result["after_one_shot_rms"].asDouble() < 0.01 * result["one_shot_rms"].asDouble());
  // The virtual panel: held, then closed → FAILSAFE on the trainee page.
  CHECK(result["virtual_held"].asString() == "OK · dead-man held");
  CHECK(result["virtual_failsafe_text"].asString().rfind("FAILSAFE", 0) == 0);
  const int64_t first = failsafe_run_start(peer.panels, result["virtual_failsafe"]["panel_utime"].asInt64());
  REQUIRE(first > 0);
  const double latency = hud_latency_ms(result["virtual_failsafe"], first);
  WARN("HUD failsafe after the virtual panel closed: PanelState published → DOM " << latency << " ms");
  CHECK(latency >= 0.0);
  CHECK(latency < 200.0);
}

TEST_CASE("rise demo --view serves the trainee page and prints its URL for the demo's robot", "[instructor]") {
  if (!fs::exists(kWeb + "/dist/trainee.html")) {
    WARN("skipped: the pages are not built (instructor/web: npm ci && node build.mjs)");
    return;
  }
  char tmpl[] = "/tmp/rise-demo-view-XXXXXX";
  const fs::path dir = ::mkdtemp(tmpl);
  const std::string id = "view" + std::to_string(::getpid());
  ChildProcess demo({kBin + "/rise", "demo", "--view", "--id", id, "--lcm", kLcm, "--log-dir", (dir / "logs").string()},
                    (dir / "demo.log").string());
  // The URL is printed once the chain is up.
  static const std::regex url_re(R"(trainee view \(camera, HUD, sound\) at http://127\.0\.0\.1:(\d+)(/trainee\.html\?id=([^&]+)&token=(\w+)))");
  std::smatch m;
  std::string out;
  for (int i = 0; i < 300 && demo.running(); ++i) {
    out = read_file((dir / "demo.log").string());
    if (std::regex_search(out, m, url_re)) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  INFO(out);
  REQUIRE(m.size() == 5);
  CHECK(m[3] == id);
  httplib::Client http("127.0.0.1", std::stoi(m[1]));
  const auto page = http.Get(m[2].str().c_str());
  REQUIRE(page);
  CHECK(page->status == 200);
  CHECK(page->body.find("trainee.js") != std::string::npos);
  const auto no_token = http.Get(("/trainee.html?id=" + id).c_str());
  REQUIRE(no_token);
  CHECK(no_token->status == 401);
  // The server hears the demo's robot.
  const auto trainees = http.Get("/api/trainees", {{"X-Rise-Token", m[4].str()}});
  REQUIRE(trainees);
  CHECK(trainees->status == 200);
  const auto list = parse_json(trainees->body);
  bool robot = false;
  for (const auto& t : list) robot |= t["id"].asString() == id && t.isMember("robot_state");
  CHECK(robot);
  demo.stop(5000);
  fs::remove_all(dir);
}

namespace {
/// A collision that goes on as rise-sim and a trainer report it: per step,
/// collision_continues of the chassis and of a wheel, and a penalty.
struct EventScript {
  lcm::LCM& lcm;
  std::string id;
  void sim(const std::string& kind, const std::string& a, const std::string& b) {
    rise_msgs::SimEvent e{};
    e.utime = rise::msgs::wall_us();
    e.robot_id = id;
    e.kind = kind;
    e.a = a;
    e.b = b;
    lcm.publish(rise::msgs::sim_event_channel(id), &e);
  }
  void penalty(int score) {
    rise_msgs::TaskEvent e{};
    e.utime = rise::msgs::wall_us();
    e.trainee_id = id;
    e.task = "drive_through";
    e.attempt = 1;
    e.name = "collision";
    e.kind = "collision";
    e.points = -1;
    e.score = score;
    lcm.publish(rise::msgs::task_event_channel(id), &e);
  }
};
}  // namespace

TEST_CASE("the console folds a collision that goes on into one line with a count and a duration", "[instructor]") {
  if (const auto why = missing_browser(); !why.empty()) {
    WARN("skipped: " << why);
    return;
  }
  Stations st(false);
  TraineePeer peer(st.id);
  REQUIRE(peer.good());
  REQUIRE(st.ready(peer));
  // A trainee of its own: rise-sim's events for st.id would interleave.
  const std::string ev_id = st.id + "ev";
  const std::string ready = (st.dir / "console_ready").string();
  ChildProcess node({"/usr/bin/node", kSource + "/tests/instructor/browser/console_fold_check.cjs", st.base(), st.token,
                     ev_id, st.out_dir(), kWeb, ready},
                    (st.dir / "console_fold_check.log").string());
  REQUIRE(peer.wait_until([&] { return fs::exists(ready) || !node.running(); }, 30000));
  EventScript script{peer.lcm(), ev_id};
  const auto pause = [&](int ms) { peer.wait_until([] { return false; }, ms); };
  script.sim("collision_started", "chassis", "wall_3");
  for (int i = 0; i < 20; ++i) {
    pause(150);
    script.sim("collision_continues", "chassis", "wall_3");
    script.sim("collision_continues", "wheel_fl", "wall_3");
    script.penalty(100 - i - 1);
  }
  script.sim("region_entered", "chassis", "dock");
  for (int i = 0; i < 3; ++i) {
    pause(150);
    script.sim("collision_continues", "chassis", "wall_3");
  }
  const bool finished = peer.wait_until([&] { return !node.running(); }, 40000);
  if (!finished) node.stop();
  const auto result = read_result((st.dir / "console_fold_check.log").string());
  INFO(read_file((st.dir / "console_fold_check.log").string()));
  REQUIRE(finished);
  REQUIRE_FALSE(result.isMember("error"));
  CHECK(result["page_errors"].size() == 0);
  // 24 events of the run and the penalties: five lines, as published.
  const auto& lines = result["lines"];
  REQUIRE(lines.size() == 5);
  CHECK(lines[0]["text"].asString() == ev_id + " collision_started chassis / wall_3");
  CHECK(lines[1]["count"].asInt() == 40);
  const std::string run = lines[1]["text"].asString();
  CHECK(run.rfind(ev_id + " collision_continues ×40 over ", 0) == 0);
  CHECK(run.find("chassis / wall_3, wheel_fl / wall_3") != std::string::npos);
  // The run spans 19 pauses of 150 ms (and whatever the machine adds).
  const double span = std::stod(run.substr(run.find(" over ") + 6));
  CHECK(span >= 2.8);
  CHECK(span < 6.0);
  CHECK(lines[2]["count"].asInt() == 20);
  CHECK(lines[2]["text"].asString().rfind(ev_id + " task collision -1 ×20 over ", 0) == 0);
  CHECK(lines[2]["text"].asString().find("→ 80") != std::string::npos);
  CHECK(lines[3]["text"].asString() == ev_id + " region_entered chassis / dock");
  CHECK(lines[4]["count"].asInt() == 3);
}


TEST_CASE("the Training Builder adds a task and a conditioned edge by clicks and typing, and rise-trainer walks the saved "
          "file through it",
          "[instructor][builder]") {
  if (const auto why = missing_browser(); !why.empty()) {
    WARN("skipped: " << why);
    return;
  }
  char tmpl[] = "/tmp/rise-builder-test-XXXXXX";
  const fs::path dir = ::mkdtemp(tmpl);
  const fs::path designs = dir / "designs";
  fs::create_directories(designs);
  for (const auto& e : fs::directory_iterator(kSource + "/sim/training/examples"))
    if (e.path().extension() == ".yaml") fs::copy_file(e.path(), designs / e.path().filename());
  const std::string file = (designs / "fig10_training.yaml").string();
  BuilderServer server(dir, designs);
  INFO(read_file((dir / "server.log").string()));
  REQUIRE(server.up);
  // Before the edit a mission 2 that scores 2 repeats.
  const std::vector<std::string> walk{"score=10,success=1", "score=2"};
  const auto before = trainer_check(dir, file, walk);
  CHECK(before.second.find("walk: mission2 #1: always → mission2") != std::string::npos);

  const std::string screens = screens_dir();
  ChildProcess node({"/usr/bin/node", kSource + "/tests/instructor/browser/training_builder_check.cjs", server.base(),
                     server.token, screens, kWeb, designs.string()},
                    (dir / "builder_check.log").string());
  const int node_code = node.wait_for(120000);
  if (node_code < 0) node.stop();
  const auto r = read_result((dir / "builder_check.log").string());
  INFO(read_file((dir / "builder_check.log").string()));
  REQUIRE(node_code == 0);
  REQUIRE_FALSE(r.isMember("error"));
  CHECK(r["page_errors"].size() == 0);
  CHECK(r["status"].asInt() == 200);
  // The shipped graph drawn: START, three tasks, END; 11 arrows, three of them repeats.
  CHECK(text(r["boxes"]) == text(parse_json(R"(["START","mission1","mission2","mission3","END"])")));
  CHECK(r["arrows"].asInt() == 11);
  // The line to the other builders and the console, this page's own marked.
  CHECK(text(r["nav"]) == text(parse_json(R"([["console_builder.html",""],["robot_builder.html",""],
    ["world_builder.html",""],["task_builder.html",""],["training.html","current"],["/",""]])")));
  CHECK(r["loop_labels"].size() == 3);
  CHECK(r["opened"]["cls"].asString() == "ok");
  // A lone task: the validator's error inline, on its line, and no saving.
  REQUIRE(r["lone_task_errors"].size() == 1);
  CHECK(r["lone_task_errors"][0]["key"].asString() == "nodes[3]");
  CHECK(r["lone_task_errors"][0]["line"].asInt() > 0);
  CHECK(r["lone_task_errors"][0]["text"].asString().find("node 'drill' is unreachable from START") != std::string::npos);
  CHECK(r["lone_task_save_disabled"].asBool());
  // A condition that is no number: the loader's own words, with line and key, the edge drawn red.
  REQUIRE(r["bad_condition_errors"].size() == 1);
  const auto& bad = r["bad_condition_errors"][0];
  CHECK(bad["key"].asString() == "transitions[6].if");
  CHECK(bad["text"].asString() ==
        std::to_string(bad["line"].asInt()) + ": transitions[6].if: condition 'score LT five': 'five' is not a number");
  CHECK(text(r["bad_edges_drawn"]) == text(parse_json(R"(["mission2→drill"])")));
  CHECK(r["edge_note"].asString().find("before the unconditional mission2 → mission2") != std::string::npos);
  REQUIRE(r["after_first_edge_errors"].size() == 1);
  CHECK(r["after_first_edge_errors"][0]["text"].asString().find("node 'drill' has no path to END") != std::string::npos);
  CHECK(r["valid"]["cls"].asString() == "ok");
  CHECK(text(r["drawn_new_edge"]) == text(parse_json(R"(["2: score LT 5"])")));
  // Someone else's change on disk: refused, said so, the file left as they wrote it.
  CHECK(r["conflict_text"].asString().find("fig10_training.yaml changed on disk since this page loaded it") !=
        std::string::npos);
  CHECK(r["save_state_after_conflict"].asString() == "not saved: changed on disk");
  const std::string disk = read_file(file);
  CHECK(disk == r["disk_after_conflict"].asString());
  CHECK(disk.find("# changed by someone else\n") != std::string::npos);
  CHECK(r["attempts_after_reload"].asString() == "1");  // the page's unsaved 3 is gone, the disk's 1 shown

  // The saved file, in the CLI: it loads, has the new task and edge in place, and the walk goes there.
  CHECK(disk.find("  - {name: drill, task: neutralize_object.yaml, max_attempts: 1}") != std::string::npos);
  CHECK(disk.find("  - {from: mission2, if: \"score LT 5\", to: drill}\n  - {from: mission2, to: mission2}") !=
        std::string::npos);
  CHECK(disk.find("# C3: Mission 2 not needed") != std::string::npos);  // the comments kept
  const auto after = trainer_check(dir, file, walk);
  INFO(after.second);
  CHECK(after.first == 0);
  CHECK(after.second.find("training fig10_metro, 4 nodes, 13 transitions: ok") != std::string::npos);
  CHECK(after.second.find("walk: mission2 #1: score LT 5 → drill") != std::string::npos);
  CHECK(trainer_check(dir, file, {"score=10,success=1", "score=2", "score=0"}).second.find("walk: drill #1: always → END") !=
        std::string::npos);
  // A mission 2 that scores 5 or more still repeats, as before the edit.
  CHECK(trainer_check(dir, file, {"score=10,success=1", "score=6"}).second.find("walk: mission2 #1: always → mission2") !=
        std::string::npos);
  CHECK(is_png(screens + "/training_builder.png"));
  CHECK(is_png(screens + "/training_builder_conflict.png"));
  server.process.stop();
  fs::remove_all(dir);
}
