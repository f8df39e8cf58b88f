// python-can (Debian's python3-can) connects to the console emulator's
// socketcand server as any lab tool would; what it records must decode,
// with our DBC, to the values the script set.

#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "process/child_process.hpp"
#include "tests/integration/integration_support.hpp"
#include "firmware_protocol/dbc.hpp"

using rise::process::ChildProcess;
using rise::test::kBin;
using rise::test::kSource;
using rise::test::python_can_available;
namespace fp = rise::firmware_protocol;

TEST_CASE("python-can receives the emulator's frames over socketcand and our DBC decodes the scripted values",
          "[integration]") {
  if (!python_can_available()) {
    WARN("skipped: /usr/bin/python3 with python3-can (Debian) is not installed");
    return;
  }
  const std::string dir =
      std::filesystem::temp_directory_path() / ("rise-pycan-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string port = std::to_string(rise::test::free_tcp_port());

  ChildProcess panel({kBin + "/rise-panel", "emulate", "--can", "socketcand+listen://127.0.0.1:" + port + "/can0",
                      "--script", kSource + "/tests/integration/python_can_script.txt", "--hold"},
                     dir + "/rise-panel.log");
  // python-can's client retries the connection for up to 10 s itself.
  ChildProcess python({"/usr/bin/python3", kSource + "/tests/integration/python_can_capture.py", "127.0.0.1", port,
                       "can0", "1.5", dir + "/capture.log"},
                      dir + "/python.log");
  REQUIRE(python.wait_for(30000) == 0);
  panel.stop();

  const auto dbc = fp::DbcDatabase::load(kSource + "/firmware_protocol/console_can_v1.dbc");
  std::ifstream in(dir + "/capture.log");
  std::map<std::string, double> last;
  std::map<std::string, int> frames_by_message;
  int lines = 0;
  for (std::string line; std::getline(in, line);) {
    // "(1700000000.123456) can0 111#0A1B..." — candump -l format.
    ++lines;
    const auto hash = line.find('#');
    const auto space = line.rfind(' ', hash);
    REQUIRE(hash != std::string::npos);
    const uint32_t id = static_cast<uint32_t>(std::stoul(line.substr(space + 1, hash - space - 1), nullptr, 16));
    std::vector<uint8_t> data;
    for (std::size_t i = hash + 1; i + 1 < line.size(); i += 2)
      data.push_back(static_cast<uint8_t>(std::stoul(line.substr(i, 2), nullptr, 16)));
    const fp::DbcMessage* message = dbc.find(id, false);
    INFO(line);
    REQUIRE(message != nullptr);
    ++frames_by_message[message->name];
    for (const auto& s : dbc.decode(*message, data)) last[s.signal->name] = s.value;
  }
  INFO("captured " << lines << " frames; logs in " << dir);
  // The firmware's rates: axes at 100 Hz, buttons/switches at 50 Hz, heartbeat at 10 Hz.
  CHECK(frames_by_message["Axes0"] >= 20);
  CHECK(frames_by_message["Buttons"] >= 10);
  CHECK(frames_by_message["Heartbeat"] >= 2);
  const double lsb = 1.0 / 32767;
  CHECK(last["Axis0"] == Approx(-0.25).margin(lsb));  // drive_x
  CHECK(last["Axis1"] == Approx(0.5).margin(lsb));    // drive_y
  CHECK(last["Axis4"] == Approx(1.0).margin(lsb));    // arm_twist
  CHECK(last["Axis2"] == Approx(0.0).margin(lsb));
  CHECK(last["Button0"] == 1.0);  // dead-man
  CHECK(last["Button1"] == 0.0);  // e-stop released
  CHECK(last["Switch0"] == 1.0);  // mode = arm
  CHECK(last["Switch1"] == 1.0);  // speed = medium
  CHECK(last["ProtocolVersion"] == 1.0);
  CHECK(last["PanelStatus"] == 1.0);  // operational
  std::filesystem::remove_all(dir);
}
