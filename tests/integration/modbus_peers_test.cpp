// Third-party Modbus peers against our programs: Debian's mbpoll reads the
// console emulator's register map and writes an LED coil; a pymodbus console
// (tests/integration/modbus_pymodbus_panel.py) is polled by rise-hild, killed
// and restarted.

#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>
#include <csignal>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <regex>
#include <sstream>
#include <thread>

#include "app/child_process.hpp"
#include "tests/integration/integration_support.hpp"
#include "firmware_protocol/console_modbus.hpp"
#include "rise_msgs/PanelState.hpp"

using rise::app::ChildProcess;
using rise::test::kBin;
using rise::test::kSource;
namespace fp = rise::firmware_protocol;

namespace {
const std::string kLcm = "udpm://239.255.76.67:7667?ttl=0";

uint16_t free_port() {
  static uint16_t next = static_cast<uint16_t>(36000 + (::getpid() % 20000));
  return next++;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

template <class Condition>
bool wait_until(Condition condition, int timeout_ms) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (!condition()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

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

float axis(const rise_msgs::PanelState& m, const std::string& name) {
  for (const auto& a : m.axes)
    if (a.name == name) return a.value;
  return 99.0f;
}
}  // namespace

TEST_CASE("mbpoll reads the emulator's register map and lights an LED through a coil", "[integration]") {
  if (!std::filesystem::exists("/usr/bin/mbpoll")) {
    WARN("skipped: mbpoll (Debian package mbpoll) is not installed");
    return;
  }
  const std::string dir = std::filesystem::temp_directory_path() / ("rise-mbpoll-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string port = std::to_string(free_port());
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
  const std::string port = std::to_string(free_port());
  const std::string panel_file = modbus_definition(dir);
  const std::vector<std::string> console_argv = {
      "/usr/bin/python3", kSource + "/tests/integration/modbus_pymodbus_panel.py", port, "16384", "-8192", "0x1"};

  lcm::LCM lcm(kLcm);
  REQUIRE(lcm.good());
  PanelStates states;
  lcm.subscribe("rise/" + id + "/panel_state", &PanelStates::on, &states);
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
