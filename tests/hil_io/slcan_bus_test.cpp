#include <catch2/catch.hpp>

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "hil/io/can_bus.hpp"
#include "hil/io/can_url.hpp"
#include "hil/io/slcan_bus.hpp"
#include "msgs/clock.hpp"
#include "tests/hil_io/slcan_test_support.hpp"
#include "tests/hil_io/test_support.hpp"

using namespace rise::hil::io;
using rise::hil::io::test::FakeAdapter;
using rise::hil::io::test::FakeAdapterOptions;
using rise::hil::io::test::make_fd_frame;
using rise::hil::io::test::make_frame;
using rise::hil::io::test::SocatPtys;
using rise::hil::io::test::TempDir;
using rise::hil::io::test::wait_until;

namespace {

std::string url_of(const SocatPtys& ptys, const std::string& query = "bitrate=500000") {
  return "slcan://" + ptys.a() + "?" + query;
}

const SlcanBus& as_slcan(const CanBus& bus) { return dynamic_cast<const SlcanBus&>(bus); }

// Receives until a frame comes or timeout_ms passed.
IoStatus receive_frame(CanBus& bus, CanFrame& frame, int timeout_ms = 2000) {
  return bus.receive(frame, timeout_ms);
}

CanFrame remote_frame(uint32_t id, uint8_t len, bool extended) {
  CanFrame f;
  f.id = id;
  f.len = len;
  f.remote = true;
  f.extended = extended;
  return f;
}

}  // namespace

#define REQUIRE_SOCAT()                                              \
  do {                                                               \
    if (!rise::hil::io::test::have_socat()) {                             \
      WARN("/usr/bin/socat is absent (Debian package socat): skip"); \
      return;                                                        \
    }                                                                \
  } while (false)

TEST_CASE("slcan URLs give the device path, the bitrate and the options", "[hil_io]") {
  SECTION("good URLs") {
    const auto plain = std::get<SlcanAddress>(parse_can_url("slcan:///dev/ttyACM0?bitrate=500000"));
    CHECK(plain.path == "/dev/ttyACM0");
    CHECK(plain.bitrate_bps == 500000);
    CHECK_FALSE(plain.listen_only);
    CHECK_FALSE(plain.timestamps);
    CHECK(plain.baud == 115200);
    const auto all = std::get<SlcanAddress>(parse_can_url(
        "SLCAN:///dev/serial/by-id/usb-CANable-if00?bitrate=125000&listen_only=1&timestamps=1&baud=921600"));
    CHECK(all.path == "/dev/serial/by-id/usb-CANable-if00");
    CHECK(all.bitrate_bps == 125000);
    CHECK(all.listen_only);
    CHECK(all.timestamps);
    CHECK(all.baud == 921600);
  }
  SECTION("bad URLs") {
    const char* bad = GENERATE("slcan://?bitrate=500000",         // missing path
                               "slcan://",                        // missing path
                               "slcan://dev/ttyACM0?bitrate=500000",  // relative path
                               "slcan:///dev/ttyACM0",            // missing bitrate
                               "slcan:///dev/ttyACM0?baud=115200",  // missing bitrate
                               "slcan:///dev/ttyACM0?bitrate=33333",
                               "slcan:///dev/ttyACM0?bitrate=500k",
                               "slcan:///dev/ttyACM0?bitrate=2000000",
                               "slcan:///dev/ttyACM0?bitrate=500000&baud=12345",
                               "slcan:///dev/ttyACM0?bitrate=500000&listen_only=yes",
                               "slcan:///dev/ttyACM0?bitrate=500000&fd=1",
                               "slcan:///dev/ttyACM0?bitrate=500000&bitrate=250000");
    CAPTURE(bad);
    CHECK_THROWS_AS(parse_can_url(bad), std::invalid_argument);
    CHECK_THROWS_AS(open_can_bus(bad), std::invalid_argument);
  }
}

TEST_CASE("slcan bitrates map to the Lawicel S codes", "[hil_io]") {
  const auto [bitrate, code] = GENERATE(table<uint32_t, int>({{10000, 0},
                                                              {20000, 1},
                                                              {50000, 2},
                                                              {100000, 3},
                                                              {125000, 4},
                                                              {250000, 5},
                                                              {500000, 6},
                                                              {800000, 7},
                                                              {1000000, 8},
                                                              {83333, -1},
                                                              {0, -1}}));
  CAPTURE(bitrate);
  CHECK(slcan_bitrate_code(bitrate) == code);
}

TEST_CASE("an slcan bus whose device is absent stays closed until reopen finds it", "[hil_io]") {
  auto bus = open_can_bus("slcan:///nonexistent/rise-slcan-tty?bitrate=500000");
  CHECK_FALSE(bus->is_open());
  CHECK(bus->last_error().find("/nonexistent/rise-slcan-tty") != std::string::npos);
  CanFrame f;
  CHECK(bus->receive(f, 0) == IoStatus::Disconnected);
  CHECK(bus->send(make_frame(0x1, {1})) == IoStatus::Disconnected);
  CHECK(bus->reopen() == IoStatus::Disconnected);
}

TEST_CASE("an slcan bus opens the adapter with C, the bitrate code and O", "[hil_io]") {
  REQUIRE_SOCAT();
  TempDir dir;
  SocatPtys ptys(dir.path());
  REQUIRE(ptys.ready());

  SECTION("each bitrate sends its S code") {
    const auto [bitrate, command] = GENERATE(table<const char*, const char*>(
        {{"10000", "S0"}, {"125000", "S4"}, {"500000", "S6"}, {"1000000", "S8"}}));
    FakeAdapter adapter(ptys.b());
    REQUIRE(adapter.opened());
    auto bus = open_can_bus(url_of(ptys, std::string("bitrate=") + bitrate));
    REQUIRE(bus->is_open());
    CHECK(adapter.commands() == std::vector<std::string>{"C", command, "O"});
    CHECK(adapter.channel_open());
    bus.reset();  // closing sends C
    CHECK(wait_until([&] { return !adapter.channel_open(); }));
    CHECK(adapter.commands().back() == "C");
  }
  SECTION("listen-only opens with L and refuses to send") {
    FakeAdapter adapter(ptys.b());
    auto bus = open_can_bus(url_of(ptys, "bitrate=250000&listen_only=1"));
    REQUIRE(bus->is_open());
    CHECK(adapter.commands() == std::vector<std::string>{"C", "S5", "L"});
    CHECK(bus->send(make_frame(0x123, {1})) == IoStatus::Error);
    CHECK(bus->last_error().find("listen-only") != std::string::npos);
  }
  SECTION("timestamps=1 turns the adapter's time stamps on before opening") {
    FakeAdapter adapter(ptys.b());
    auto bus = open_can_bus(url_of(ptys, "bitrate=500000&timestamps=1"));
    REQUIRE(bus->is_open());
    CHECK(adapter.commands() == std::vector<std::string>{"C", "S6", "Z1", "O"});
  }
  SECTION("an adapter that refuses the bitrate leaves the bus closed with the reason") {
    FakeAdapterOptions options;
    options.refuse = 'S';
    FakeAdapter adapter(ptys.b(), options);
    SlcanBus bus(url_of(ptys), std::get<SlcanAddress>(parse_can_url(url_of(ptys))));
    CHECK(bus.reopen() == IoStatus::Error);
    CHECK_FALSE(bus.is_open());
    CHECK(bus.last_error().find("refused S6") != std::string::npos);
  }
}

TEST_CASE("slcan frames cross the pty pair with identical content both ways", "[hil_io]") {
  REQUIRE_SOCAT();
  TempDir dir;
  SocatPtys ptys(dir.path());
  REQUIRE(ptys.ready());
  FakeAdapterOptions options;
  options.ack_transmit = GENERATE(false, true);  // CANUSB acknowledges t/T with z/Z
  FakeAdapter adapter(ptys.b(), options);
  auto bus = open_can_bus(url_of(ptys));
  REQUIRE(bus->is_open());

  const std::vector<CanFrame> frames = {
      make_frame(0x123, {0x11, 0x22, 0x33}),
      make_frame(0x1ABCDEF0, {0xDE, 0xAD}, true),
      make_frame(0x7FF, {}),
      make_frame(0x5, {1, 2, 3, 4, 5, 6, 7, 0xFF}, true),
      remote_frame(0x321, 2, false),
      remote_frame(0x1FFFFFFF, 8, true),
  };
  const std::vector<std::string> expected = {"t1233112233", "T1ABCDEF02DEAD", "t7FF0",
                                             "T00000005801020304050607FF", "r3212", "R1FFFFFFF8"};

  // Bus → adapter: the exact Lawicel text.
  for (const CanFrame& f : frames) REQUIRE(bus->send(f) == IoStatus::Ok);
  REQUIRE(wait_until([&] { return adapter.frame_lines().size() == frames.size(); }));
  CHECK(adapter.frame_lines() == expected);

  // Adapter → bus: the same lines come back as the same frames; the answers
  // to our sends (\r or z/Z) are skipped on the way.
  for (const std::string& line : expected) REQUIRE(adapter.write(line + "\r"));
  for (const CanFrame& f : frames) {
    CanFrame got;
    REQUIRE(receive_frame(*bus, got) == IoStatus::Ok);
    CHECK(same_content(got, f));
    CHECK(got.timestamp_us > 0);
  }
  CanFrame extra;
  CHECK(bus->receive(extra, 0) == IoStatus::Timeout);
  CHECK(as_slcan(*bus).garbage_lines() == 0);
  CHECK(as_slcan(*bus).error_replies() == 0);
}

TEST_CASE("slcan send refuses what classic slcan cannot carry", "[hil_io]") {
  REQUIRE_SOCAT();
  TempDir dir;
  SocatPtys ptys(dir.path());
  REQUIRE(ptys.ready());
  FakeAdapter adapter(ptys.b());
  auto bus = open_can_bus(url_of(ptys));
  REQUIRE(bus->is_open());

  CanFrame error_frame = make_frame(0x4, {0, 0, 0, 0, 0, 0, 0, 0});
  error_frame.error = true;
  CanFrame too_big_id = make_frame(0x800, {1});
  CHECK(bus->send(make_fd_frame(0x42, 64, true)) == IoStatus::Invalid);
  CHECK(bus->send(make_fd_frame(0x42, 8, false)) == IoStatus::Invalid);
  CHECK(bus->send(error_frame) == IoStatus::Invalid);
  CHECK(bus->send(too_big_id) == IoStatus::Invalid);
  // Nothing reached the adapter; the bus still works.
  REQUIRE(bus->send(make_frame(0x10, {0xAB})) == IoStatus::Ok);
  REQUIRE(wait_until([&] { return !adapter.frame_lines().empty(); }));
  CHECK(adapter.frame_lines() == std::vector<std::string>{"t0101AB"});
}

TEST_CASE("slcan timestamps come from the adapter clock across its 60 s wrap", "[hil_io]") {
  REQUIRE_SOCAT();
  TempDir dir;
  SocatPtys ptys(dir.path());
  REQUIRE(ptys.ready());
  FakeAdapter adapter(ptys.b());

  SECTION("timestamps=1: the adapter's millisecond stamps space the frames") {
    auto bus = open_can_bus(url_of(ptys, "bitrate=500000&timestamps=1"));
    REQUIRE(bus->is_open());
    // 59990 ms, then 10 ms after the wrap: 20 ms apart; then 1.5 s later.
    REQUIRE(adapter.write("t1230EA56\rt1231AA000A\rT000000FF0064A\r"));
    CanFrame first, second, third;
    REQUIRE(receive_frame(*bus, first) == IoStatus::Ok);
    REQUIRE(receive_frame(*bus, second) == IoStatus::Ok);
    REQUIRE(receive_frame(*bus, third) == IoStatus::Ok);
    CHECK(same_content(second, make_frame(0x123, {0xAA})));
    CHECK(same_content(third, make_frame(0xFF, {}, true)));
    CHECK(second.timestamp_us - first.timestamp_us == 20'000);
    // 0x064A = 1610 ms: 1.6 s after the second frame by the adapter, but the
    // host saw no time pass, so the adapter clock is anchored again.
    CHECK(third.timestamp_us - second.timestamp_us < 1'000'000);
    CHECK(as_slcan(*bus).garbage_lines() == 0);
  }
  SECTION("timestamps=0: a stamped line still parses, with the host's receive time") {
    auto bus = open_can_bus(url_of(ptys));
    REQUIRE(bus->is_open());
    const int64_t before_us = rise::msgs::wall_us();
    REQUIRE(adapter.write("t1231AA000A\r"));
    CanFrame got;
    REQUIRE(receive_frame(*bus, got) == IoStatus::Ok);
    CHECK(same_content(got, make_frame(0x123, {0xAA})));
    CHECK(got.timestamp_us >= before_us);
  }
}

TEST_CASE("slcan receive skips and counts garbage and over-long lines", "[hil_io]") {
  REQUIRE_SOCAT();
  TempDir dir;
  SocatPtys ptys(dir.path());
  REQUIRE(ptys.ready());
  FakeAdapter adapter(ptys.b());
  auto bus = open_can_bus(url_of(ptys));
  REQUIRE(bus->is_open());

  const std::string noise =
      "hello\r"                       // not a frame
      "t12\r"                         // cut id
      "t1232AA\r"                     // one byte short
      "t1239\r"                       // DLC 9
      "t80010\r"                      // 12-bit id in a standard frame
      "t123" "1GG\r"                  // not hex
      "t1231AA12\r"                   // 2 digits left over: neither data nor a time stamp
      "t1230EA61\r"                   // time stamp 60001 ms: past the wrap
      + std::string(200, '7') + "\r"  // over-long
      + "T" + std::string(40, '1') + "\r"  // over-long, frame-like
      + "\a"                          // BELL: an answer, not a line
      + "\r\n"                        // empty lines: OK answers
      + "t4561" "5A\r";
  REQUIRE(adapter.write(noise));
  CanFrame got;
  REQUIRE(receive_frame(*bus, got) == IoStatus::Ok);
  CHECK(same_content(got, make_frame(0x456, {0x5A})));
  CHECK(as_slcan(*bus).garbage_lines() == 10);
  CHECK(as_slcan(*bus).error_replies() == 1);

  SECTION("a line split across reads is joined") {
    REQUIRE(adapter.write("T1234"));
    CHECK(bus->receive(got, 20) == IoStatus::Timeout);
    REQUIRE(adapter.write("56781CC\r"));
    REQUIRE(receive_frame(*bus, got) == IoStatus::Ok);
    CHECK(same_content(got, make_frame(0x12345678, {0xCC}, true)));
  }
  SECTION("the stream recovers after an over-long line without a terminator yet") {
    REQUIRE(adapter.write(std::string(100, 'x')));
    CHECK(bus->receive(got, 20) == IoStatus::Timeout);
    REQUIRE(adapter.write("\rt0010\r"));
    REQUIRE(receive_frame(*bus, got) == IoStatus::Ok);
    CHECK(same_content(got, make_frame(0x001, {})));
    CHECK(as_slcan(*bus).garbage_lines() == 11);
  }
}

TEST_CASE("an slcan bus reports Disconnected when the pty goes away and reopens on a new one",
          "[hil_io]") {
  REQUIRE_SOCAT();
  TempDir dir;
  auto ptys = std::make_unique<SocatPtys>(dir.path());
  REQUIRE(ptys->ready());
  auto adapter = std::make_unique<FakeAdapter>(ptys->b());
  auto bus = open_can_bus(url_of(*ptys));
  REQUIRE(bus->is_open());
  REQUIRE(adapter->write("t1001AA\r"));
  CanFrame got;
  REQUIRE(receive_frame(*bus, got) == IoStatus::Ok);

  // Unplug: socat ends, both pty ends hang up.
  ptys->stop();
  CHECK(wait_until([&] { return adapter->hung_up(); }));
  CHECK(bus->receive(got, 2000) == IoStatus::Disconnected);
  CHECK_FALSE(bus->is_open());
  CHECK_FALSE(bus->last_error().empty());
  CHECK(bus->send(make_frame(0x1, {})) == IoStatus::Disconnected);
  CHECK(bus->reopen() == IoStatus::Disconnected);  // the link is gone with socat
  adapter.reset();

  // Plug in again: a new pty pair on the same link path.
  ptys = std::make_unique<SocatPtys>(dir.path());
  REQUIRE(ptys->ready());
  adapter = std::make_unique<FakeAdapter>(ptys->b());
  REQUIRE(bus->reopen() == IoStatus::Ok);
  CHECK(bus->is_open());
  CHECK(bus->last_error().empty());
  CHECK(adapter->commands() == std::vector<std::string>{"C", "S6", "O"});
  REQUIRE(bus->send(make_frame(0x200, {0x01, 0x02})) == IoStatus::Ok);
  REQUIRE(wait_until([&] { return !adapter->frame_lines().empty(); }));
  CHECK(adapter->frame_lines() == std::vector<std::string>{"t20020102"});
  REQUIRE(adapter->write("T1FFFFFFF0\r"));
  REQUIRE(receive_frame(*bus, got) == IoStatus::Ok);
  CHECK(same_content(got, make_frame(0x1FFFFFFF, {}, true)));
}
