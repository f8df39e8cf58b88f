#include <catch2/catch.hpp>

#include <cstdlib>
#include <fstream>

#include "hil/io/candump_log.hpp"

using namespace rise::hil::io;

TEST_CASE("candump log lines of every frame kind are read as can-utils writes them", "[hil_io]") {
  SECTION("classic") {
    const auto r = parse_candump_line("(1436509052.249713) can0 123#DEADBEEF\n");
    REQUIRE(r.ok());
    CHECK(r.record.interface == "can0");
    CHECK(r.record.frame.timestamp_us == 1436509052249713);
    CHECK(r.record.frame.id == 0x123);
    CHECK(r.record.frame.len == 4);
    CHECK(r.record.frame.data[0] == 0xDE);
    CHECK_FALSE(r.record.frame.extended);
  }
  SECTION("extended, remote, FD, error") {
    auto r = parse_candump_line("(1.000001) vcan0 12345678#00");
    REQUIRE(r.ok());
    CHECK(r.record.frame.extended);
    CHECK(r.record.frame.id == 0x12345678);
    r = parse_candump_line("(1.5) can1 7FF#R4");
    REQUIRE(r.ok());
    CHECK(r.record.frame.remote);
    CHECK(r.record.frame.len == 4);
    CHECK(r.record.frame.timestamp_us == 1'500'000);
    r = parse_candump_line("(2.000000) can0 123##1" + std::string(128, 'A'));
    REQUIRE(r.ok());
    CHECK(r.record.frame.fd);
    CHECK(r.record.frame.brs);
    CHECK(r.record.frame.len == 64);
    r = parse_candump_line("(3.000000) can0 20000004#0004000000000000");
    REQUIRE(r.ok());
    CHECK(r.record.frame.error);
    CHECK(r.record.frame.id == 0x4);
  }
  SECTION("malformed lines give a typed error") {
    CHECK(parse_candump_line("").error == CandumpError::Empty);
    CHECK(parse_candump_line("can0 123#00").error == CandumpError::NoTimestamp);
    CHECK(parse_candump_line("(99999999999999999999.0) can0 123#00").error == CandumpError::NoTimestamp);
    CHECK(parse_candump_line("(.5) can0 123#00").error == CandumpError::NoTimestamp);
    CHECK(parse_candump_line("(1.0) can0 800#00").error == CandumpError::BadId);
    CHECK(parse_candump_line("(1.0) can0 1234#00").error == CandumpError::BadId);
    CHECK(parse_candump_line("(1.0) can0 123#0").error == CandumpError::BadData);
    CHECK(parse_candump_line("(1.0) can0 123#XY").error == CandumpError::BadData);
    CHECK(parse_candump_line("(1.0) can0 123#001122334455667788").error == CandumpError::TooLong);
    CHECK(parse_candump_line("(1.0) can0 123##1001122334455667788").error == CandumpError::BadData);  // 9: no FD length
  }
}

TEST_CASE("every line of the real ICSim capture reads and writes back unchanged", "[hil_io]") {
  const char* root = std::getenv("RISE_TEST_DATA");
  const std::string path = std::string(root ? root : "") + "/can/ICSim/sample-can.log";
  std::ifstream in(path);
  if (!root || !in) {
    WARN("skipped: " << path << " is absent (RISE_TEST_DATA)");
    return;
  }
  int lines = 0;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto r = parse_candump_line(line);
    INFO(line);
    REQUIRE(r.ok());
    CHECK(format_candump_line(r.record.frame, r.record.interface) == line);
    ++lines;
  }
  CHECK(lines == 6158);  // MANIFEST.md: 6158 classic frames
}

TEST_CASE("a candump line's direction reads back as written: R received, T sent, none received", "[hil_io]") {
  const auto f = rise::hil::io::parse_candump_line("(1.000001) can0 123#DEADBEEF").record.frame;
  const auto [direction, text, tx] = GENERATE(table<CandumpDirection, std::string, bool>({
      {CandumpDirection::None, "(1.000001) can0 123#DEADBEEF", false},
      {CandumpDirection::Received, "(1.000001) can0 123#DEADBEEF R", false},
      {CandumpDirection::Sent, "(1.000001) can0 123#DEADBEEF T", true},
  }));
  CHECK(format_candump_line(f, "can0", direction) == text);
  const auto r = parse_candump_line(text);
  REQUIRE(r.ok());
  CHECK(r.record.tx == tx);
  CHECK(same_content(r.record.frame, f));
  std::string reused;
  reused.reserve(256);
  const auto* data = reused.data();
  append_candump_line(reused, f, "can0", direction);
  CHECK(reused == text);
  CHECK(reused.data() == data);  // no allocation into a buffer with the room
}
