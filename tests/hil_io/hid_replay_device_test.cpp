// replay://FILE.hid (HidReplayDevice): a hid-recorder file played as the
// device, timed against the wall clock: each report at its due time, plugs
// and unplugs where the recording has them, Disconnected at the end; speed,
// fast, loop and the start/stop window; URLs and files it refuses.

#include <catch2/catch.hpp>

#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "hil/io/hid_recording.hpp"
#include "hil/io/hid_replay_device.hpp"
#include "tests/hid_test_devices.hpp"

using namespace rise::hil::io;
using Clock = std::chrono::steady_clock;

namespace {

constexpr int64_t t0 = 1'700'000'000'000'000;

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("rise_hidreplay_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

HidIdentity identity(const char* name) {
  HidIdentity id;
  id.name = name;
  id.bus = 3;
  id.vendor_id = 0x0428;
  id.product_id = 0x4001;
  return id;
}

const std::vector<uint8_t> gravis(std::begin(rise::test::gravis_descriptor), std::end(rise::test::gravis_descriptor));
const std::vector<uint8_t> other_descriptor = {0x05, 0x01, 0x09, 0x04, 0xa1, 0x01, 0xc0};

// A plug at t0, then `n` one-byte reports (0, 1, 2, ...) every step_ms from t0 + 50 ms.
std::string write_reports(const std::string& name, int n, int step_ms) {
  const std::string path = temp_path(name);
  HidRecordingWriter w(path, "pad");
  w.plug(t0, gravis, identity("pad"));
  for (int i = 0; i < n; ++i) w.report(t0 + 50'000 + int64_t{i} * step_ms * 1000, std::vector<uint8_t>{static_cast<uint8_t>(i)});
  return path;
}

double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

// Reads until Disconnected (bounded): each report's first byte and when it came.
struct Played {
  std::vector<int> values;
  std::vector<double> at_ms;
  double end_ms = -1;
};
Played play(HidReplayDevice& device, Clock::time_point start, double limit_ms = 10'000) {
  Played p;
  std::array<uint8_t, max_hid_report_bytes> report{};
  while (ms_since(start) < limit_ms) {
    std::size_t length = 0;
    const IoStatus st = device.read(report, length, 20);
    if (st == IoStatus::Ok) {
      p.values.push_back(report[0]);
      p.at_ms.push_back(ms_since(start));
    } else if (st == IoStatus::Disconnected) {
      p.end_ms = ms_since(start);
      break;
    }
  }
  return p;
}

}  // namespace

TEST_CASE("hid replay hands out each report at its due time, then reads as unplugged for good", "[hil_io]") {
  const double speed = GENERATE(1.0, 2.0);
  const std::string path = write_reports("timed.hid", 20, 10);
  HidReplayDevice device("replay://" + path + (speed == 1.0 ? "" : "?speed=2"));
  CHECK_FALSE(device.is_open());
  CHECK(device.hotplug_active());
  const auto start = Clock::now();
  REQUIRE(device.reopen() == IoStatus::Ok);
  CHECK(device.report_descriptor() == gravis);
  CHECK(device.identity() == identity("pad"));
  const Played p = play(device, start);
  REQUIRE(p.values.size() == 20);
  for (std::size_t i = 0; i < p.values.size(); ++i) {
    INFO("report " << i);
    CHECK(p.values[i] == static_cast<int>(i));
    const double due_ms = (50.0 + 10.0 * static_cast<double>(i)) / speed;
    CHECK(p.at_ms[i] >= due_ms - 0.5);  // never early (steady clock granularity aside)
    CHECK(p.at_ms[i] <= due_ms + 8.0);  // the margin of ReplayBus's tests: a loaded 2-core machine
  }
  WARN("speed " << speed << ": max lateness " << device.max_lateness_us() << " us over 20 reports");
  CHECK(device.max_lateness_us() < 8000);
  // The end: unplugged right after the last report, and it never comes back.
  CHECK(p.end_ms >= p.at_ms.back());
  CHECK(p.end_ms <= p.at_ms.back() + 8.0);
  CHECK(device.ended());
  CHECK_FALSE(device.is_open());
  CHECK(device.reopen() == IoStatus::Disconnected);
  CHECK(device.last_error() == path + ": end of the recording");
  CHECK_FALSE(device.wait_for_arrival(1));
  CHECK(device.reports_played() == 20);
  std::filesystem::remove(path);
}

TEST_CASE("hid replay with fast=1 hands out every report at once, with the recorded order", "[hil_io]") {
  const std::string path = write_reports("fast.hid", 200, 100);  // 20 s of recording
  HidReplayDevice device("replay://" + path + "?fast=1");
  const auto start = Clock::now();
  REQUIRE(device.reopen() == IoStatus::Ok);
  const Played p = play(device, start);
  REQUIRE(p.values.size() == 200);
  CHECK(p.values.back() == 199);
  CHECK(p.end_ms < 1000.0);
  CHECK(device.max_lateness_us() == 0);
  std::filesystem::remove(path);
}

TEST_CASE("hid replay unplugs and plugs in again where the recording does, with the new descriptor", "[hil_io]") {
  const std::string path = temp_path("replug.hid");
  {
    HidRecordingWriter w(path, "pad");
    w.plug(t0, gravis, identity("first"));
    w.report(t0 + 20'000, std::vector<uint8_t>{1});
    w.unplug(t0 + 100'000, "gone");
    w.plug(t0 + 200'000, other_descriptor, identity("second"));
    w.report(t0 + 220'000, std::vector<uint8_t>{2});
    w.end(t0 + 300'000);
  }
  HidReplayDevice device("replay://" + path);
  const auto start = Clock::now();
  REQUIRE(device.reopen() == IoStatus::Ok);
  Played p = play(device, start);
  REQUIRE(p.values == std::vector<int>{1});
  CHECK(p.end_ms == Approx(100.0).margin(8.0));
  CHECK_FALSE(device.is_open());
  CHECK(device.last_error() == path + ":8: unplugged");  // the line of its `# unplugged at`
  // Away until the plug is due: the bridge's enumeration finds nothing, its wait ends at the plug.
  CHECK(device.reopen() == IoStatus::Disconnected);
  CHECK(device.last_error() == path + ": not plugged in yet");
  bool arrived = false;
  while (!arrived && ms_since(start) < 2000) arrived = device.wait_for_arrival(5);
  REQUIRE(arrived);
  CHECK(ms_since(start) == Approx(200.0).margin(8.0));
  REQUIRE(device.reopen() == IoStatus::Ok);
  CHECK(device.report_descriptor() == other_descriptor);
  CHECK(device.identity().name == "second");
  CHECK(device.plugs_played() == 2);
  p = play(device, start);
  CHECK(p.values == std::vector<int>{2});
  CHECK(p.end_ms == Approx(300.0).margin(8.0));  // the recording's end, not its last report
  CHECK(device.ended());
  std::filesystem::remove(path);
}

TEST_CASE("hid replay takes a further R: block without an unplug as the device plugged in again", "[hil_io]") {
  const std::string path = temp_path("blocks.hid");
  std::ofstream(path) << "R: 2 05 01\nN: a\nI: 3 1 2\nE: 000000.000000 1 01\n"
                         "R: 3 05 01 09\nN: b\nI: 3 1 2\nE: 000000.050000 1 02\n";
  HidReplayDevice device("replay://" + path);
  const auto start = Clock::now();
  REQUIRE(device.reopen() == IoStatus::Ok);
  Played p = play(device, start);
  CHECK(p.values == std::vector<int>{1});
  CHECK(device.last_error().find("plugged in again") != std::string::npos);
  REQUIRE(device.reopen() == IoStatus::Ok);  // due at once
  CHECK(device.identity().name == "b");
  CHECK(device.report_descriptor() == std::vector<uint8_t>{0x05, 0x01, 0x09});
  p = play(device, start);
  REQUIRE(p.values == std::vector<int>{2});
  CHECK(p.at_ms[0] == Approx(50.0).margin(8.0));
  std::filesystem::remove(path);
}

TEST_CASE("hid replay loops without an unplug, and plays the start/stop window plugged in", "[hil_io]") {
  const std::string path = write_reports("loop.hid", 5, 10);  // plug at 0, reports at 50..90 ms
  SECTION("loop=2: three passes, each after the last by the mean record gap") {
    HidReplayDevice device("replay://" + path + "?loop=2");
    const auto start = Clock::now();
    REQUIRE(device.reopen() == IoStatus::Ok);
    const Played p = play(device, start);
    CHECK(p.values == std::vector<int>{0, 1, 2, 3, 4, 0, 1, 2, 3, 4, 0, 1, 2, 3, 4});
    CHECK(device.loops_done() == 2);
    CHECK(device.plugs_played() == 1);  // no unplug between passes
    // A pass spans 90 ms (plug to last report) over 6 records: 18 ms gap; pass 2's first report is due at 158 ms.
    CHECK(p.at_ms[5] == Approx(158.0).margin(8.0));
  }
  SECTION("start=0.065 stop=0.085: reports 2 and 3, the device plugged in at the window's start") {
    HidReplayDevice device("replay://" + path + "?start=0.065&stop=0.085");
    const auto start = Clock::now();
    REQUIRE(device.reopen() == IoStatus::Ok);
    CHECK(device.report_descriptor() == gravis);
    const Played p = play(device, start);
    CHECK(p.values == std::vector<int>{2, 3});
    CHECK(p.at_ms[0] == Approx(5.0).margin(8.0));  // 70 ms in the file, 5 ms after the window's start
  }
  std::filesystem::remove(path);
}

TEST_CASE("hid replay of hid-tools' device files plugs in and plays no report", "[hil_io]") {
  const char* root = std::getenv("RISE_TEST_DATA");
  const std::string path = root ? std::string(root) + "/hid/hid-tools_PS3Controller.hid" : std::string();
  if (path.empty() || !std::filesystem::exists(path)) {
    WARN("RISE_TEST_DATA has no hid/hid-tools_PS3Controller.hid: skipped");
    return;
  }
  HidReplayDevice device("replay://" + path);
  REQUIRE(device.reopen() == IoStatus::Ok);
  CHECK(device.report_descriptor().size() == 148);
  CHECK(device.identity().vendor_id == 0x054c);
  CHECK(device.identity().product_id == 0x0268);
  std::array<uint8_t, 64> report{};
  std::size_t length = 0;
  CHECK(device.read(report, length, 10) == IoStatus::Disconnected);
  CHECK(device.ended());
  CHECK(device.reports_played() == 0);
}

TEST_CASE("hid replay drops output reports, counted, while open", "[hil_io]") {
  const std::string path = write_reports("write.hid", 1, 10);
  HidReplayDevice device("replay://" + path);
  const std::vector<uint8_t> leds = {0x02, 0x01};
  CHECK(device.write(leds) == IoStatus::Disconnected);
  REQUIRE(device.reopen() == IoStatus::Ok);
  CHECK(device.write(leds) == IoStatus::Ok);
  CHECK(device.writes_dropped() == 1);
  std::filesystem::remove(path);
}

TEST_CASE("hid replay refuses CAN-only options, a missing file and a file that is not hid-recorder's", "[hil_io]") {
  const std::string path = write_reports("refuse.hid", 1, 10);
  const std::string option = GENERATE("ids=123", "channel=can0", "step=1");
  INFO(option);
  CHECK_THROWS_WITH(HidReplayDevice("replay://" + path + "?" + option),
                    Catch::Contains("ids=, channel= and step= are for CAN logs"));
  CHECK_THROWS_AS(HidReplayDevice("replay://" + path + "?speed=0"), std::invalid_argument);
  CHECK_THROWS_WITH(HidReplayDevice("replay:///nonexistent/x.hid"),
                    Catch::Contains("/nonexistent/x.hid: cannot open: No such file or directory"));
  const std::string candump = temp_path("frames.log");
  std::ofstream(candump) << "(1700000000.000000) can0 123#00\n";
  CHECK_FALSE(looks_like_hid_recording(candump));
  CHECK_THROWS_WITH(HidReplayDevice("replay://" + candump), Catch::StartsWith(candump + ":1: (: not a hid-recorder line"));
  std::filesystem::remove(candump);
  std::filesystem::remove(path);
}
