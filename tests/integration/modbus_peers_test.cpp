// Third-party Modbus peers against our programs: Debian's mbpoll reads the
// console emulator's register map and writes an LED coil; a pymodbus console
// (tests/integration/modbus_pymodbus_panel.py) is polled by rise-hild, killed
// and restarted; a pymodbus PLC with a register map of its own
// (modbus_pymodbus_plc.py) is read through the points of
// panels/definitions/modbus_plc_panel.yaml, with mbpoll beside it; and
// rise-hild takes a recorded trace (replay://) for the console.

#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>
#include <csignal>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <regex>
#include <sstream>
#include <thread>

#include "firmware_protocol/console_modbus.hpp"
#include "msgs/channels.hpp"
#include "msgs/clock.hpp"
#include "msgs/panel_state_controls.hpp"
#include "process/child_process.hpp"
#include "rise_msgs/PanelFeedback.hpp"
#include "rise_msgs/PanelState.hpp"
#include "tests/integration/integration_support.hpp"
#include "tests/process_support.hpp"

using rise::process::ChildProcess;
using rise::test::kBin;
using rise::test::kSource;
namespace fp = rise::firmware_protocol;

namespace {
using rise::test::read_file;
using rise::test::wait_until;

const std::string kLcm = rise::msgs::kDefaultLcmUrl;

// mbpoll's "[address]: value" lines → value by address (unsigned column).
std::map<int, long> parse_mbpoll(const std::string& text) {
  std::map<int, long> values;
  static const std::regex line(R"(\[(\d+)\]:\s+(-?\d+))");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), line); it != std::sregex_iterator(); ++it)
    values[std::stoi((*it)[1])] = std::stol((*it)[2]);
  return values;
}

// Runs mbpoll to completion; its output in `out`. The exit code, -1 if it hung.
int run_mbpoll(const std::vector<std::string>& args, const std::string& log, std::string& out) {
  std::filesystem::remove(log);
  std::vector<std::string> argv = {"/usr/bin/mbpoll"};
  argv.insert(argv.end(), args.begin(), args.end());
  ChildProcess p(argv, log);
  const int rc = p.wait_for(10000);
  out = read_file(log);
  return rc;
}

// The reference console with its source switched to rise-modbus-v1.
std::string modbus_definition(const std::string& dir) {
  std::string yaml = read_file(kSource + "/panels/definitions/rise_console.yaml");
  const std::string from = "protocol: rise-can-v1\n    node: 0";
  yaml.replace(yaml.find(from), from.size(), "protocol: rise-modbus-v1\n    unit: 1\n    poll_hz: 100");
  const std::string timeout = "timeout_ms: 50";
  yaml.replace(yaml.find(timeout), timeout.size(), "timeout_ms: 100");
  const std::string path = dir + "/rise_console_modbus.yaml";
  std::ofstream(path) << yaml;
  return path;
}

struct PanelStates {
  std::mutex mutex;
  std::vector<rise_msgs::PanelState> messages;
  void on(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::PanelState* m) {
    std::lock_guard lock(mutex);
    messages.push_back(*m);
  }
  template <class Pred>
  std::optional<rise_msgs::PanelState> find(Pred pred, std::size_t from = 0) {
    std::lock_guard lock(mutex);
    for (std::size_t i = from; i < messages.size(); ++i)
      if (pred(messages[i])) return messages[i];
    return std::nullopt;
  }
  std::size_t size() {
    std::lock_guard lock(mutex);
    return messages.size();
  }
};

// A missing control reads as a value no assertion expects.
float axis(const rise_msgs::PanelState& m, const std::string& name) {
  return rise::msgs::find_axis(m, name).value_or(99.0f);
}

std::string switch_label(const rise_msgs::PanelState& m, const std::string& name) {
  return rise::msgs::find_switch_label(m, name).value_or("?");
}

bool pymodbus_available() {
  ChildProcess probe({"/usr/bin/python3", "-c", "import pymodbus.server"}, "/dev/null");
  return probe.wait_for(20000) == 0;
}

// Handles LCM on its own thread until it is destroyed (however the test ends).
class LcmListener {
 public:
  explicit LcmListener(lcm::LCM& lcm) : thread_([this, &lcm] {
    while (on_) lcm.handleTimeout(20);
  }) {}
  ~LcmListener() {
    on_ = false;
    thread_.join();
  }
  LcmListener(const LcmListener&) = delete;
  LcmListener& operator=(const LcmListener&) = delete;

 private:
  std::atomic<bool> on_{true};
  std::thread thread_;
};

// `rise-hild verify` replays a --record directory against its own PanelState log: it passes.
void check_verifies(const std::string& panel, const std::string& record_dir) {
  ChildProcess verify({kBin + "/rise-hild", "verify", "--panel", panel, "--record-dir", record_dir},
                      record_dir + "-verify.log");
  CHECK(verify.wait_for(30000) == 0);
  const std::string out = read_file(record_dir + "-verify.log");
  INFO(out);
  CHECK(out.find("pass: ") == 0);
}

// Replaces `path` at once (the PLC script re-reads it when it changes).
void write_state(const std::string& path, const std::string& text) {
  std::ofstream(path + ".new") << text;
  std::filesystem::rename(path + ".new", path);
}
}  // namespace

TEST_CASE("mbpoll reads the emulator's register map and lights an LED through a coil", "[integration]") {
  if (!std::filesystem::exists("/usr/bin/mbpoll")) {
    WARN("skipped: mbpoll (Debian package mbpoll) is not installed");
    return;
  }
  const std::string dir = std::filesystem::temp_directory_path() / ("rise-mbpoll-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string port = std::to_string(rise::test::free_tcp_port());
  ChildProcess panel({kBin + "/rise-panel", "emulate", "--modbus", "modbus+tcp-listen://127.0.0.1:" + port + "?unit=1",
                      "--script", kSource + "/tests/integration/modbus_script.txt", "--hold"},
                     dir + "/rise-panel.log");
  INFO("logs in " << dir);
  REQUIRE(wait_until([&] { return read_file(dir + "/rise-panel.log").find("rise-panel ready") != std::string::npos; },
                     10000));

  // Input registers 0..17, 0-based (-0), one poll (-1).
  std::string out;
  std::map<int, long> regs;
  REQUIRE(wait_until(
      [&] {
        return run_mbpoll({"-m", "tcp", "-a", "1", "-0", "-r", "0", "-c", "18", "-t", "3", "-1", "-p", port,
                           "127.0.0.1"},
                          dir + "/mbpoll-ir.log", out) == 0 &&
               (regs = parse_mbpoll(out)).size() == 18 && regs[1] != 0;
      },
      10000));
  INFO(out);
  CHECK(regs[1] == fp::axis_from_unit(0.5f));                          // drive_y = axis.1
  CHECK(static_cast<int16_t>(regs[2]) == fp::axis_from_unit(-0.25f));  // arm_x = axis.2 (unsigned column)
  CHECK(regs[7] == 2);                                                 // speed = switch.1 "fast"
  CHECK(regs[12] == 1);                                                // Operational
  CHECK(regs[13] == 1);                                                // version 1
  std::array<uint16_t, fp::modbus_ir::kCount> block{};
  for (std::size_t i = 0; i < block.size(); ++i) block[i] = static_cast<uint16_t>(regs[static_cast<int>(i)]);
  CHECK(fp::decode_inputs(block, 0).ok());  // the CRC register matches what mbpoll read

  // Discrete inputs 0..3: the dead-man (button.0) is held.
  REQUIRE(run_mbpoll({"-m", "tcp", "-a", "1", "-0", "-r", "0", "-c", "4", "-t", "1", "-1", "-p", port, "127.0.0.1"},
                     dir + "/mbpoll-di.log", out) == 0);
  const auto bits = parse_mbpoll(out);
  CHECK(bits.at(0) == 1);
  CHECK(bits.at(1) == 0);

  // Coil 1 is the "fault" LED.
  REQUIRE(run_mbpoll({"-m", "tcp", "-a", "1", "-0", "-r", "1", "-t", "0", "-p", port, "127.0.0.1", "1"},
                     dir + "/mbpoll-coil.log", out) == 0);
  CHECK(wait_until(
      [&] { return read_file(dir + "/rise-panel.log").find("feedback: leds power=off fault=on") != std::string::npos; },
      5000));
  CHECK(panel.stop() == 0);
  std::filesystem::remove_all(dir);
}

TEST_CASE("rise-hild polls a pymodbus console, fails safe when it is killed and reconnects when it returns",
          "[integration]") {
  ChildProcess probe({"/usr/bin/python3", "-c", "import pymodbus.server"}, "/dev/null");
  if (probe.wait_for(20000) != 0) {
    WARN("skipped: /usr/bin/python3 with python3-pymodbus (and python3-serial-asyncio) is not installed");
    return;
  }
  const std::string id = "mbtest" + std::to_string(::getpid());
  const std::string dir = std::filesystem::temp_directory_path() / ("rise-pymodbus-" + id);
  std::filesystem::create_directories(dir);
  const std::string port = std::to_string(rise::test::free_tcp_port());
  const std::string panel_file = modbus_definition(dir);
  const std::vector<std::string> console_argv = {
      "/usr/bin/python3", kSource + "/tests/integration/modbus_pymodbus_panel.py", port, "16384", "-8192", "0x1"};

  lcm::LCM lcm(kLcm);
  REQUIRE(lcm.good());
  PanelStates states;
  lcm.subscribe(rise::msgs::panel_state_channel(id), &PanelStates::on, &states);
  std::atomic<bool> listening{true};
  std::thread listener([&] {
    while (listening) lcm.handleTimeout(20);
  });

  auto console = std::make_unique<ChildProcess>(console_argv, dir + "/console.log");
  ChildProcess hild({kBin + "/rise-hild", "--panel", panel_file, "--source",
                     "modbus+tcp://127.0.0.1:" + port + "?unit=1&timeout_ms=50", "--id", id, "--lcm", kLcm},
                    dir + "/rise-hild.log");
  INFO("logs in " << dir);

  const float expected_x = (0.5f - 0.05f) / 0.95f, expected_y = -(0.25f - 0.05f) / 0.95f;
  REQUIRE(wait_until([&] { return states.find([](const auto& m) { return !m.failsafe && m.deadman; }).has_value(); },
                     15000));
  const auto live = *states.find([](const auto& m) { return !m.failsafe && m.deadman; });
  CHECK(axis(live, "drive_x") == Approx(expected_x).margin(1e-3));
  CHECK(axis(live, "drive_y") == Approx(expected_y).margin(1e-3));
  REQUIRE(live.sources.size() == 1);
  CHECK(live.sources[0].url.find("modbus+tcp://") == 0);
  CHECK(live.sources[0].frames_ok > 0);
  // The bridge's "power" LED reached the console as coil 0.
  CHECK(wait_until([&] { return read_file(dir + "/console.log").find("leds 0x00000001") != std::string::npos; }, 5000));

  // Kill the console: failsafe within timeout_ms + one publish period.
  const std::size_t before = states.size();
  console->signal(SIGKILL);
  REQUIRE(console->wait_for(5000) == 128 + SIGKILL);
  REQUIRE(wait_until([&] { return states.find([](const auto& m) { return m.failsafe; }, before).has_value(); }, 5000));
  const auto lost = *states.find([](const auto& m) { return m.failsafe; }, before);
  CHECK(axis(lost, "drive_x") == 0.0f);
  CHECK(lost.sources[0].last_frame_age_us <= 100000 + 10000 + 15000);
  {
    // No message after the loss was published as safe with older data.
    std::lock_guard lock(states.mutex);
    for (const auto& m : states.messages)
      if (m.sources[0].last_frame_age_us > 100000) CHECK(m.failsafe);
  }

  // It comes back: rise-hild reconnects (back-off at most 2 s).
  const std::size_t lost_at = states.size();
  console = std::make_unique<ChildProcess>(console_argv, dir + "/console2.log");
  REQUIRE(wait_until([&] { return states.find([](const auto& m) { return !m.failsafe; }, lost_at).has_value(); },
                     15000));
  const auto back = *states.find([](const auto& m) { return !m.failsafe; }, lost_at);
  CHECK(back.sources[0].reconnects >= 1);
  CHECK(axis(back, "drive_y") == Approx(expected_y).margin(1e-3));

  CHECK(hild.stop() == 0);
  console->stop();
  listening = false;
  listener.join();
  std::filesystem::remove_all(dir);
}

TEST_CASE("rise-hild reads a pymodbus PLC through the points of its definition, writes its LEDs and display, fails "
          "safe when it is killed and recovers when it returns, with mbpoll writing and reading beside it, and the "
          "recording verifies",
          "[integration]") {
  if (!pymodbus_available()) {
    WARN("skipped: /usr/bin/python3 with python3-pymodbus (and python3-serial-asyncio) is not installed");
    return;
  }
  const bool mbpoll = std::filesystem::exists("/usr/bin/mbpoll");
  const std::string id = "plctest" + std::to_string(::getpid());
  const std::string dir = std::filesystem::temp_directory_path() / ("rise-plc-" + id);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string port = std::to_string(rise::test::free_tcp_port());
  const std::string panel_file = kSource + "/panels/definitions/modbus_plc_panel.yaml";
  const std::string state = dir + "/plc_state.txt";
  // drive_x -500 of ±1000 (int16), drive_y 250, lift 4095 of 0..4095; the dead-man held; speed "medium".
  write_state(state, "ir 0 65036 250 4095 0 0 0\ndi 0 1 0\nhr 3 1\n");
  const std::vector<std::string> plc_argv = {"/usr/bin/python3", kSource + "/tests/integration/modbus_pymodbus_plc.py",
                                             port, state};

  lcm::LCM lcm(kLcm);
  REQUIRE(lcm.good());
  PanelStates states;
  lcm.subscribe(rise::msgs::panel_state_channel(id), &PanelStates::on, &states);
  const LcmListener listener(lcm);

  auto plc = std::make_unique<ChildProcess>(plc_argv, dir + "/plc.log");
  ChildProcess hild({kBin + "/rise-hild", "--panel", panel_file, "--source",
                     "modbus+tcp://127.0.0.1:" + port + "?unit=1&timeout_ms=50", "--id", id, "--lcm", kLcm,
                     "--record", dir + "/record"},
                    dir + "/rise-hild.log");
  INFO("logs in " << dir);

  const auto live_now = [](const rise_msgs::PanelState& m) { return !m.failsafe && m.deadman; };
  REQUIRE(wait_until([&] { return states.find(live_now).has_value(); }, 15000));
  const auto live = *states.find(live_now);
  CHECK(axis(live, "drive_x") == Approx(-(0.5f - 0.05f) / 0.95f).margin(1e-4));
  CHECK(axis(live, "drive_y") == Approx((0.25f - 0.05f) / 0.95f).margin(1e-4));
  CHECK(axis(live, "lift") == Approx(1.0f).margin(1e-6));
  CHECK(switch_label(live, "speed") == "medium");
  REQUIRE(live.sources.size() == 1);
  CHECK(live.sources[0].connected);
  CHECK(live.sources[0].frames_ok > 0);

  // The test moves the PLC's inputs: the next poll carries them.
  write_state(state, "ir 0 0 1000 0 0 0 0\ndi 0 1 0\nhr 3 2\n");
  CHECK(wait_until([&] {
    return states.find([](const auto& m) { return switch_label(m, "speed") == "fast" && axis(m, "drive_y") == 1.0f; })
        .has_value();
  }, 5000));
  if (mbpoll) {
    // A third-party master writes the selector's holding register: rise-hild reads it.
    std::string out;
    CHECK(run_mbpoll({"-m", "tcp", "-a", "1", "-0", "-r", "3", "-t", "4", "-1", "-p", port, "127.0.0.1", "0"},
                     dir + "/mbpoll-hr.log", out) == 0);
    const std::size_t from = states.size();
    CHECK(wait_until([&] { return states.find([](const auto& m) { return switch_label(m, "speed") == "slow"; }, from)
                                  .has_value(); }, 5000));
  }

  // Feedback from LCM: the display and the beacon LED reach the PLC's holding registers.
  rise_msgs::PanelFeedback feedback{};
  feedback.panel_id = "plc-panel";
  feedback.num_leds = 1;
  feedback.led_names = {"beacon"};
  feedback.led_on = {true};
  feedback.num_displays = 1;
  feedback.display_names = {"speed"};
  feedback.display_values = {1.25f};
  int sent = 0;
  CHECK(wait_until([&] {
    if (sent++ % 20 == 0) {
      feedback.utime = rise::msgs::wall_us();
      lcm.publish(rise::msgs::panel_feedback_channel(id), &feedback);
    }
    const std::string log = read_file(dir + "/plc.log");
    return log.find("hr 10 = 125") != std::string::npos && log.find("hr 12 = 1") != std::string::npos;
  }, 5000));
  const std::string plc_log = read_file(dir + "/plc.log");
  CHECK(plc_log.find("coil 0 = 1") != std::string::npos);  // power
  CHECK(plc_log.find("coil 3 = 1") == std::string::npos);  // fault: never lit while the PLC answered
  if (mbpoll) {
    // ... and a third-party master reads them back: power lit, fault dark.
    std::string out;
    REQUIRE(run_mbpoll({"-m", "tcp", "-a", "1", "-0", "-r", "0", "-c", "4", "-t", "0", "-1", "-p", port, "127.0.0.1"},
                       dir + "/mbpoll-coils.log", out) == 0);
    const auto coils = parse_mbpoll(out);
    CHECK(coils.at(0) == 1);
    CHECK(coils.at(3) == 0);
  }

  // Kill the PLC: failsafe within a poll period and a publish period (plus scheduling).
  const std::size_t before = states.size();
  const int64_t killed_us = rise::msgs::wall_us();
  plc->signal(SIGKILL);
  REQUIRE(plc->wait_for(5000) == 128 + SIGKILL);
  REQUIRE(wait_until([&] { return states.find([](const auto& m) { return m.failsafe; }, before).has_value(); }, 5000));
  const auto lost = *states.find([](const auto& m) { return m.failsafe; }, before);
  CHECK(axis(lost, "drive_y") == 0.0f);
  CHECK(axis(lost, "lift") == -1.0f);
  CHECK(lost.failsafe_reason.find("plc: ") == 0);
  CHECK(lost.utime - killed_us <= 20'000 + 10'000 + 15'000);
  REQUIRE(wait_until([&] { return states.find([](const auto& m) { return m.failsafe_reason == "plc: disconnected"; },
                                              before).has_value(); }, 5000));

  // It comes back with the same inputs: rise-hild reconnects and writes the feedback again.
  const std::size_t lost_at = states.size();
  plc = std::make_unique<ChildProcess>(plc_argv, dir + "/plc2.log");
  REQUIRE(wait_until([&] { return states.find(live_now, lost_at).has_value(); }, 15000));
  const auto back = *states.find(live_now, lost_at);
  CHECK(back.sources[0].reconnects >= 1);
  CHECK(axis(back, "drive_y") == 1.0f);
  CHECK(wait_until([&] {
    const std::string log = read_file(dir + "/plc2.log");
    return log.find("coil 0 = 1") != std::string::npos && log.find("hr 10 = 125") != std::string::npos;
  }, 5000));
  {
    // No message between the loss and the return was published as safe.
    std::lock_guard lock(states.mutex);
    for (std::size_t i = before; i < states.messages.size() && states.messages[i].utime < back.utime; ++i)
      if (states.messages[i].utime > lost.utime) CHECK(states.messages[i].failsafe);
  }

  CHECK(hild.stop() == 0);
  plc->stop();

  // The recording replays to what rise-hild published (functions 02, 03, 04, 15, 16).
  const std::string trace = read_file(dir + "/record/plc.modbus.log");
  CHECK(trace.find(" fc=03 addr=3 count=1 ") != std::string::npos);
  CHECK(trace.find(" fc=15 addr=0 count=1 ") != std::string::npos);
  check_verifies(panel_file, dir + "/record");
  std::filesystem::remove_all(dir);
}

TEST_CASE("rise-hild plays a recorded Modbus trace by replay:// as the console, publishing the session on LCM and "
          "failing safe at its end, and its own recording of the replay verifies",
          "[integration]") {
  const std::string id = "mbreplay" + std::to_string(::getpid());
  const std::string dir = std::filesystem::temp_directory_path() / ("rise-mbreplay-" + id);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string panel = kSource + "/panels/definitions/rise_console_modbus.yaml";
  lcm::LCM lcm(kLcm);
  REQUIRE(lcm.good());
  PanelStates states;
  lcm.subscribe(rise::msgs::panel_state_channel(id), &PanelStates::on, &states);
  const LcmListener listener(lcm);

  // The 2.01 s session at speed 2.
  ChildProcess hild({kBin + "/rise-hild", "--panel", panel, "--source",
                     "replay://" + kSource + "/tests/data/replay/modbus/console.modbus.log?speed=2", "--id", id,
                     "--lcm", kLcm, "--record", dir + "/record"},
                    dir + "/rise-hild.log");
  INFO("logs in " << dir);
  const auto healthy_now = [](const rise_msgs::PanelState& m) { return !m.failsafe; };
  REQUIRE(wait_until([&] { return states.find(healthy_now).has_value(); }, 10000));
  const auto healthy = *states.find(healthy_now);
  const auto driving_now = [](const rise_msgs::PanelState& m) {
    return !m.failsafe && m.deadman && std::fabs(axis(m, "drive_y") - (0.8f - 0.05f) / 0.95f) < 1e-3f;
  };
  const auto end_now = [&](const rise_msgs::PanelState& m) {
    return m.utime > healthy.utime && m.failsafe_reason == "console: disconnected";
  };
  REQUIRE(wait_until([&] { return states.find(end_now).has_value(); }, 5000));
  CHECK(states.find(driving_now).has_value());
  const auto end = *states.find(end_now);
  CHECK(static_cast<double>(end.utime - healthy.utime) * 1e-6 == Approx(2.01 / 2).margin(0.05));
  CHECK(end.sources[0].url.find("replay://") == 0);
  CHECK(hild.stop() == 0);

  check_verifies(panel, dir + "/record");
  std::filesystem::remove_all(dir);
}
