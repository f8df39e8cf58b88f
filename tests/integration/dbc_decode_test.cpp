// rise-hild dbc decode on real car captures with the DBC their author used:
// the coverage must be what the data's manifest states.

#include <catch2/catch.hpp>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "process/child_process.hpp"

namespace {
std::string read_all(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}
}  // namespace

TEST_CASE("rise-hild dbc decode prints one line per frame and the coverage of a real capture", "[integration]") {
  const char* root = std::getenv("RISE_TEST_DATA");
  const std::string dbc = std::string(root ? root : "") + "/can/opendbc/toyota_iQ_2009_can.dbc";
  const std::string log = std::string(root ? root : "") + "/can/CANBUSlogs-yaris09/steering.log";
  if (!root || !std::filesystem::exists(dbc) || !std::filesystem::exists(log)) {
    WARN("skipped: the Yaris capture or its DBC is absent under RISE_TEST_DATA");
    return;
  }
  const std::string out = std::filesystem::temp_directory_path() / ("rise-dbc-" + std::to_string(::getpid()) + ".txt");
  rise::process::ChildProcess p({std::string(RISE_BINARY_DIR) + "/bin/rise-hild", "dbc", "decode", dbc, log}, out);
  REQUIRE(p.wait_for(30000) == 0);
  const std::string text = read_all(out);
  std::filesystem::remove(out);
  // MANIFEST.md: 1769 frames, 64 % with a message in toyota_iQ_2009_can.dbc.
  CHECK(text.find("# 1769 frames: 1128 with a message") != std::string::npos);
  CHECK(std::count(text.begin(), text.end(), '\n') == 1769 + 1);
  CHECK(text.find("3B3#0B3828 :: LOW_RES_INDICATORS(LOW_RES_ACC_PEDAL: 20, LOW_RES_RPM: 2872 rpm)") !=
        std::string::npos);
}

TEST_CASE("rise-hild hid describe lists the fields of a real gamepad's descriptor and refuses a broken one",
          "[integration]") {
  const char* root = std::getenv("RISE_TEST_DATA");
  const std::string file = std::string(root ? root : "") + "/hid/android-cts/gravis_gamepadprousb_register.json";
  if (!root || !std::filesystem::exists(file)) {
    WARN("skipped: the Gravis GamePad Pro descriptor is absent under RISE_TEST_DATA");
    return;
  }
  const std::string dir = std::filesystem::temp_directory_path() / ("rise-hid-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  rise::process::ChildProcess good({std::string(RISE_BINARY_DIR) + "/bin/rise-hild", "hid", "describe", file},
                               dir + "/good.txt");
  REQUIRE(good.wait_for(30000) == 0);
  const std::string text = read_all(dir + "/good.txt");
  // MANIFEST.md: 8-bit X/Y and 10 buttons.
  CHECK(text.find("bit 0 size 8 count 2") != std::string::npos);
  CHECK(text.find("-> x y") != std::string::npos);
  CHECK(text.find("button_10") != std::string::npos);

  { std::ofstream(dir + "/bad.hex") << "05 01 09\n"; }
  rise::process::ChildProcess bad({std::string(RISE_BINARY_DIR) + "/bin/rise-hild", "hid", "describe", dir + "/bad.hex"},
                              dir + "/bad.txt");
  CHECK(bad.wait_for(30000) == 2);
  CHECK(read_all(dir + "/bad.txt").find("bad.hex:1:") != std::string::npos);
  std::filesystem::remove_all(dir);
}
