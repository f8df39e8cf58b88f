#include <catch2/catch.hpp>

#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "hil/io/can_bus.hpp"
#include "hil/io/can_url.hpp"
#include "hil/io/candump_log.hpp"
#include "hil/io/replay_bus.hpp"

using namespace rise::hil::io;

namespace {

constexpr int64_t kLogStartUs = 1'700'000'000'000'000;

// A candump log of n frames, one every step_ms: id 0x100 + i on can0 for
// even i and can1 for odd i, one data byte i.
struct TempFiles {
  std::vector<std::filesystem::path> paths;
  ~TempFiles() {
    std::error_code ignored;
    for (const auto& p : paths) std::filesystem::remove(p, ignored);
  }
};
TempFiles temp_logs;

std::string write_log(const std::string& name, int n, int step_ms) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("rise_replay_" + std::to_string(::getpid()) + "_" + name + ".log");
  temp_logs.paths.push_back(path);
  std::ofstream out(path);
  for (int i = 0; i < n; ++i) {
    CanFrame f;
    f.id = static_cast<uint32_t>(0x100 + i);
    f.len = 1;
    f.data[0] = static_cast<uint8_t>(i);
    f.timestamp_us = kLogStartUs + int64_t{i} * step_ms * 1000;
    out << format_candump_line(f, i % 2 == 0 ? "can0" : "can1") << "\n";
  }
  return path.string();
}

std::unique_ptr<ReplayBus> open_replay(const std::string& url) {
  auto bus = open_can_bus(url);
  auto* replay = dynamic_cast<ReplayBus*>(bus.get());
  REQUIRE(replay != nullptr);
  bus.release();
  return std::unique_ptr<ReplayBus>(replay);
}

// Every frame until the bus reports the end (bounded, so a bug cannot hang the test).
std::vector<CanFrame> drain(CanBus& bus) {
  std::vector<CanFrame> frames;
  CanFrame f;
  for (int i = 0; i < 10'000; ++i) {
    const IoStatus s = bus.receive(f, 1000);
    if (s == IoStatus::Disconnected) break;
    if (s == IoStatus::Ok) frames.push_back(f);
  }
  return frames;
}

}  // namespace

TEST_CASE("replay URL takes speed, loop, window, ids, channel and fast", "[hil_io]") {
  SECTION("good") {
    const auto a = std::get<ReplayAddress>(
        parse_can_url("replay:///tmp/x.log?speed=2.5&loop=-1&start=1&stop=2.5&ids=123,1ABCDEF0&channel=can1&fast=1"));
    CHECK(a.path == "/tmp/x.log");
    CHECK(a.speed == Approx(2.5).margin(1e-12));
    CHECK(a.loop == -1);
    CHECK(a.start_s == Approx(1.0).margin(1e-12));
    CHECK(a.stop_s == Approx(2.5).margin(1e-12));
    CHECK(a.ids == std::vector<uint32_t>{0x123, 0x1ABCDEF0});
    CHECK(a.channel == "can1");
    CHECK(a.fast);
    const auto plain = std::get<ReplayAddress>(parse_can_url("replay://trace.asc"));
    CHECK(plain.path == "trace.asc");
    CHECK(plain.loop == 0);
    CHECK_FALSE(plain.fast);
  }
  SECTION("bad") {
    CHECK_THROWS_AS(parse_can_url("replay://"), std::invalid_argument);
    CHECK_THROWS_AS(parse_can_url("replay://x.log?speed=0"), std::invalid_argument);
    CHECK_THROWS_AS(parse_can_url("replay://x.log?loop=-2"), std::invalid_argument);
    CHECK_THROWS_AS(parse_can_url("replay://x.log?start=2&stop=1"), std::invalid_argument);
    CHECK_THROWS_AS(parse_can_url("replay://x.log?ids=XYZ"), std::invalid_argument);
    CHECK_THROWS_AS(parse_can_url("replay://x.log?bogus=1"), std::invalid_argument);
  }
  SECTION("a missing log fails at open, naming the path") {
    CHECK_THROWS_WITH(open_can_bus("replay:///nonexistent/trace.log"),
                      Catch::Contains("/nonexistent/trace.log"));
  }
}

TEST_CASE("fast replay plays every frame in order with the recorded timestamps, then disconnects", "[hil_io]") {
  const std::string path = write_log("fast", 5, 100);
  auto bus = open_replay("replay://" + path + "?fast=1");
  REQUIRE(bus->is_open());
  const auto frames = drain(*bus);
  REQUIRE(frames.size() == 5);
  for (size_t i = 0; i < frames.size(); ++i) {
    CHECK(frames[i].id == 0x100 + i);
    CHECK(frames[i].len == 1);
    CHECK(frames[i].data[0] == i);
    CHECK(frames[i].timestamp_us == kLogStartUs + static_cast<int64_t>(i) * 100'000);
  }
  CHECK(bus->frames_played() == 5);
  CHECK_FALSE(bus->is_open());
  CanFrame f;
  CHECK(bus->receive(f, 0) == IoStatus::Disconnected);

  SECTION("send is accepted and dropped") {
    CHECK(bus->send(frames[0]) == IoStatus::Ok);
    CHECK(bus->sends_dropped() == 1);
  }
  SECTION("reopen plays it again from the start") {
    REQUIRE(bus->reopen() == IoStatus::Ok);
    CHECK(bus->is_open());
    REQUIRE(bus->receive(f, 0) == IoStatus::Ok);
    CHECK(f.id == 0x100);
    CHECK(f.timestamp_us == kLogStartUs);
  }
}

TEST_CASE("replay loops the log the asked number of times with rising timestamps", "[hil_io]") {
  const std::string path = write_log("loop", 4, 10);
  auto bus = open_replay("replay://" + path + "?fast=1&loop=2");
  const auto frames = drain(*bus);
  REQUIRE(frames.size() == 12);
  CHECK(bus->loops_done() == 2);
  for (size_t i = 0; i < frames.size(); ++i) CHECK(frames[i].id == 0x100 + i % 4);
  for (size_t i = 1; i < frames.size(); ++i) CHECK(frames[i].timestamp_us > frames[i - 1].timestamp_us);
  // 30 ms per pass plus one mean gap (10 ms) between passes.
  CHECK(frames[4].timestamp_us - frames[0].timestamp_us == 40'000);
}

TEST_CASE("replay window, id and channel filters pick the frames", "[hil_io]") {
  const std::string path = write_log("filter", 10, 100);  // records at 0.0 .. 0.9 s
  SECTION("start/stop in seconds from the first record") {
    auto bus = open_replay("replay://" + path + "?fast=1&start=0.2&stop=0.5");
    const auto frames = drain(*bus);
    REQUIRE(frames.size() == 4);
    CHECK(frames.front().id == 0x102);
    CHECK(frames.back().id == 0x105);
  }
  SECTION("ids") {
    auto bus = open_replay("replay://" + path + "?fast=1&ids=103,107,7FF");
    const auto frames = drain(*bus);
    REQUIRE(frames.size() == 2);
    CHECK(frames[0].id == 0x103);
    CHECK(frames[1].id == 0x107);
  }
  SECTION("channel") {
    auto bus = open_replay("replay://" + path + "?fast=1&channel=can1");
    const auto frames = drain(*bus);
    REQUIRE(frames.size() == 5);
    for (const auto& f : frames) CHECK(f.id % 2 == 1);
  }
  SECTION("a filter that matches nothing ends the replay even when looping forever") {
    auto bus = open_replay("replay://" + path + "?fast=1&loop=-1&ids=7FF");
    CHECK(drain(*bus).empty());
    CHECK_FALSE(bus->is_open());
  }
}

TEST_CASE("replay at speed 10 hands out each frame at its due time", "[hil_io]") {
  // Records every 200 ms: due every 20 ms after the first receive.
  const std::string path = write_log("timing", 6, 200);
  auto bus = open_replay("replay://" + path + "?speed=10");
  using Clock = std::chrono::steady_clock;
  CanFrame f;
  REQUIRE(bus->receive(f, 1000) == IoStatus::Ok);
  const auto t0 = Clock::now();
  const int64_t wall0 = f.timestamp_us;
  CHECK(f.id == 0x100);

  SECTION("a poll before the next frame is due times out") {
    CHECK(bus->receive(f, 0) == IoStatus::Timeout);
  }
  SECTION("frames come at t0 + (ts - ts0) / speed") {
    for (int i = 1; i < 6; ++i) {
      REQUIRE(bus->receive(f, 1000) == IoStatus::Ok);
      const auto at_us = std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - t0).count();
      CHECK(f.id == static_cast<uint32_t>(0x100 + i));
      CHECK(at_us == Approx(i * 20'000).margin(8'000));
      // Received frames carry the wall-clock time, like a device's.
      CHECK(f.timestamp_us - wall0 == Approx(i * 20'000).margin(8'000));
    }
    CHECK(bus->max_lateness_us() >= 0);
    CHECK(bus->max_lateness_us() < 8'000);
    CHECK(bus->frames_played() == 6);
    CHECK(bus->receive(f, 1000) == IoStatus::Disconnected);
  }
  SECTION("a late reader gets the overdue frames at once and no drift afterwards") {
    std::this_thread::sleep_until(t0 + std::chrono::milliseconds(45));  // the reader comes late: the condition under test
    REQUIRE(bus->receive(f, 0) == IoStatus::Ok);  // due at 20 ms
    REQUIRE(bus->receive(f, 0) == IoStatus::Ok);  // due at 40 ms
    CHECK(f.id == 0x102);
    CHECK(bus->max_lateness_us() >= 5'000);
    REQUIRE(bus->receive(f, 1000) == IoStatus::Ok);  // due at 60 ms, not 45 + 20
    const auto at_us = std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - t0).count();
    CHECK(f.id == 0x103);
    CHECK(at_us == Approx(60'000).margin(8'000));
  }
}

TEST_CASE("replay reads ASC and TRC logs too", "[hil_io]") {
  const char* root = std::getenv("RISE_TEST_DATA");
  const std::string path = std::string(root ? root : "") + "/can/python-can/test_CanMessage.trc";
  if (root == nullptr || !std::filesystem::exists(path)) {
    WARN("skipped: " << path << " is absent (RISE_TEST_DATA)");
    return;
  }
  auto bus = open_replay("replay://" + path + "?fast=1&channel=1");
  const auto frames = drain(*bus);
  REQUIRE(frames.size() == 1);
  CHECK(frames[0].id == 0x6F9);
  CHECK(frames[0].timestamp_us == 17'876'708);
}

TEST_CASE("replay in step mode hands out one frame per step and reports its progress", "[hil_io]") {
  const std::string log = write_log("step", 10, 1000);  // 1 s between frames: timing would show
  auto bus = open_replay("replay://" + log + "?step=1");
  CanFrame f;
  CHECK(bus->receive(f, 20) == IoStatus::Timeout);
  bus->step(2);
  REQUIRE(bus->receive(f, 20) == IoStatus::Ok);
  CHECK(f.id == 0x100);
  CHECK(f.timestamp_us == kLogStartUs);  // the recorded time: a step has no wall-clock due time
  REQUIRE(bus->receive(f, 20) == IoStatus::Ok);
  CHECK(f.id == 0x101);
  CHECK(bus->receive(f, 20) == IoStatus::Timeout);
  auto p = bus->progress();
  CHECK(p.log_time_s == Approx(1.0).margin(1e-6));

  // A step from another thread wakes a receive that waits for it: the
  // stepper steps once receive() below is waiting.
  CHECK_FALSE(bus->awaiting_step());
  std::thread stepper([&] {
    while (!bus->awaiting_step()) std::this_thread::yield();
    bus->step(8);
  });
  std::vector<uint32_t> ids;
  for (int i = 0; i < 8; ++i) {
    REQUIRE(bus->receive(f, 5000) == IoStatus::Ok);
    ids.push_back(f.id);
  }
  stepper.join();
  CHECK_FALSE(bus->awaiting_step());
  CHECK(ids.back() == 0x109);
  p = bus->progress();
  CHECK(p.fraction == Approx(1.0));
  CHECK(p.log_time_s == Approx(9.0).margin(1e-6));
  CHECK(bus->receive(f, 20) == IoStatus::Disconnected);
}
