// rise-panel replay plays a capture onto a live transport like canplayer:
// python-can's socketcand client (Debian python3-can) receives every frame of
// the capture, in order, with the capture's timing.

#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <vector>

#include "process/child_process.hpp"
#include "tests/integration/integration_support.hpp"
#include "hil/io/candump_log.hpp"

using rise::process::ChildProcess;
using rise::test::kBin;
using rise::test::kSource;
using rise::test::python_can_available;

TEST_CASE("rise-panel replay plays a capture onto socketcand and python-can receives it frame for frame",
          "[integration]") {
  if (!python_can_available()) {
    WARN("skipped: /usr/bin/python3 with python3-can (Debian) is not installed");
    return;
  }
  const std::string dir = std::filesystem::temp_directory_path() / ("rise-replay-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  // 200 frames, 2.5 ms apart (0.5 s), ids and payloads varied per frame.
  std::vector<rise::hil::io::CanFrame> sent;
  {
    std::ofstream log(dir + "/capture.log");
    for (int i = 0; i < 200; ++i) {
      rise::hil::io::CanFrame f;
      f.id = static_cast<uint32_t>(0x100 + (i * 37) % 0x600);
      f.len = static_cast<uint8_t>(i % 9);
      for (uint8_t b = 0; b < f.len; ++b) f.data[b] = static_cast<uint8_t>(i * 7 + b);
      f.timestamp_us = 1'700'000'000'000'000 + int64_t{i} * 2500;
      log << rise::hil::io::format_candump_line(f, "can0") << "\n";
      sent.push_back(f);
    }
  }
  const std::string port = std::to_string(rise::test::free_tcp_port());
  ChildProcess replay({kBin + "/rise-panel", "replay", dir + "/capture.log", "--to",
                       "socketcand+listen://127.0.0.1:" + port + "/can0", "--wait-peer"},
                      dir + "/rise-panel.log");
  ChildProcess python({"/usr/bin/python3", kSource + "/tests/integration/python_can_capture.py", "127.0.0.1", port,
                       "can0", "2.0", dir + "/received.log"},
                      dir + "/python.log");
  REQUIRE(python.wait_for(30000) == 0);
  CHECK(replay.wait_for(10000) == 0);  // it ends at the end of the capture

  std::ifstream in(dir + "/received.log");
  std::vector<rise::hil::io::CanFrame> received;
  for (std::string line; std::getline(in, line);) {
    const auto parsed = rise::hil::io::parse_candump_line(line);
    INFO(line);
    REQUIRE(parsed.ok());
    received.push_back(parsed.record.frame);
  }
  INFO("logs in " << dir);
  REQUIRE(received.size() == sent.size());
  for (std::size_t i = 0; i < sent.size(); ++i) {
    INFO("frame " << i);
    CHECK(received[i].id == sent[i].id);
    CHECK(received[i].len == sent[i].len);
    CHECK(std::equal(sent[i].data.begin(), sent[i].data.begin() + sent[i].len, received[i].data.begin()));
  }
  // The capture's timing, anchored to the wall clock: 0.4975 s first to last.
  const double span_s = static_cast<double>(received.back().timestamp_us - received.front().timestamp_us) / 1e6;
  CHECK(span_s == Approx(0.4975).margin(0.05));
}
