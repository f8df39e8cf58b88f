#include <catch2/catch.hpp>

#include <unistd.h>

#include <chrono>
#include <filesystem>

#include "hil/io/can_log.hpp"
#include "hil/io/recording_bus.hpp"
#include "msgs/clock.hpp"

using namespace rise::hil::io;

TEST_CASE("a recorded bus writes every frame it sends and receives as a candump log that reads and replays back",
          "[hil_io]") {
  const std::string dir = std::filesystem::temp_directory_path() / ("rise-rec-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/console.log";
  std::vector<CanFrame> sent;
  {
    RecordingBus recorded(open_can_bus("mem://recording_test"), path, "console");
    auto peer = open_can_bus("mem://recording_test");
    for (uint32_t i = 0; i < 20; ++i) {
      CanFrame f;
      f.id = 0x100 + i;
      f.len = static_cast<uint8_t>(i % 9);
      for (uint8_t k = 0; k < f.len; ++k) f.data[k] = static_cast<uint8_t>(i * 7 + k);
      f.extended = i % 5 == 4;
      f.timestamp_us = 1'700'000'000'000'000 + i * 1000;
      if (i % 2) {
        REQUIRE(peer->send(f) == IoStatus::Ok);
        CanFrame got;
        REQUIRE(recorded.receive(got, 1000) == IoStatus::Ok);
      } else {
        REQUIRE(recorded.send(f) == IoStatus::Ok);
      }
      sent.push_back(f);
    }
    CanFrame fd;
    fd.id = 0x7FF;
    fd.fd = fd.brs = true;
    fd.len = 64;
    fd.timestamp_us = 1'700'000'000'100'000;
    REQUIRE(recorded.send(fd) == IoStatus::Ok);
    sent.push_back(fd);
    CHECK(recorded.frames_recorded() == 21);
  }
  const auto records = read_can_log(path);
  REQUIRE(records.size() == sent.size());
  for (std::size_t i = 0; i < sent.size(); ++i) {
    INFO(i);
    CHECK(records[i].channel == "console");
    CHECK(same_content(records[i].frame, sent[i]));
  }
  // And the daemon can replay what it recorded.
  auto replay = open_can_bus("replay://" + path + "?fast=1");
  CanFrame f;
  std::size_t n = 0;
  while (replay->receive(f, 100) == IoStatus::Ok) CHECK(same_content(f, sent[n++]));
  CHECK(n == sent.size());
  std::filesystem::remove_all(dir);
}

TEST_CASE("a recorded bus marks sent frames T and received ones R, and can stamp them when they are read",
          "[hil_io]") {
  const std::string dir = std::filesystem::temp_directory_path() / ("rise-rec-dir-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/console.log";
  CanFrame old;
  old.id = 0x130;
  old.len = 2;
  old.timestamp_us = 1'000'000;  // a transport's stamp long ago
  int64_t before = 0, after = 0;
  {
    RecordingBus recorded(open_can_bus("mem://recording_stamp"), path, "console", RecordingBus::Stamp::Receive);
    auto peer = open_can_bus("mem://recording_stamp");
    REQUIRE(peer->send(old) == IoStatus::Ok);
    before = rise::msgs::wall_us();
    CanFrame got;
    REQUIRE(recorded.receive(got, 1000) == IoStatus::Ok);
    after = rise::msgs::wall_us();
    REQUIRE(recorded.send(old) == IoStatus::Ok);
  }
  const auto records = read_can_log(path);
  REQUIRE(records.size() == 2);
  CHECK_FALSE(records[0].tx);
  CHECK(records[0].frame.timestamp_us >= before);
  CHECK(records[0].frame.timestamp_us <= after);
  CHECK(records[1].tx);
  CHECK(records[1].frame.timestamp_us == old.timestamp_us);  // a sent frame keeps its own time
  std::filesystem::remove_all(dir);
}

TEST_CASE("a recorded bus whose disk is full counts the lost frames and passes the traffic on", "[hil_io]") {
  RecordingBus recorded(open_can_bus("mem://recording_full"), "/dev/full", "console");
  CanFrame f;
  f.id = 0x110;
  f.len = 8;
  // Frames are flushed every 100 ms; the first flush onto /dev/full fails.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (recorded.write_errors() == 0 && std::chrono::steady_clock::now() < deadline)
    REQUIRE(recorded.send(f) == IoStatus::Ok);
  CHECK(recorded.write_errors() > 0);
}
