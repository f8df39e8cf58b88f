// replay://FILE.modbus.log as a ModbusLink (ReplayModbusLink) on a small
// hand-written trace whose every line is a case of the header's semantics:
// answers by request and time, a timeout, an exception, the recorded link
// down and up again, dropped writes, the window, loops and the end.

#include <catch2/catch.hpp>

#include <unistd.h>

#include <array>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "hil/io/replay_modbus_link.hpp"
#include "msgs/clock.hpp"

using namespace rise::hil::io;

namespace {

constexpr int64_t kT0 = 100'000'000;  // the trace's first record: (100.000000)

// Input registers 0..1 every 100 ms with a timeout, an exception and a lost
// slave among them; coils 3..4 twice; one write.
const char* const kTrace =
    "# rise-hild modbus trace v1\n"
    "(100.000000) plc link open\n"
    "(100.000000) plc unit=1 fc=04 addr=0 count=2 rtt_us=50 ok 0001 0002\n"
    "(100.000100) plc unit=1 fc=01 addr=3 count=2 rtt_us=50 ok 10\n"
    "(100.000200) plc unit=1 fc=15 addr=0 count=1 rtt_us=40 ok 1\n"
    "(100.100000) plc unit=1 fc=04 addr=0 count=2 rtt_us=50 ok 0003 0004\n"
    "(100.100100) plc unit=1 fc=01 addr=3 count=2 rtt_us=50 ok 01\n"
    "(100.200000) plc unit=1 fc=04 addr=0 count=2 rtt_us=30000 timeout closed\n"
    "(100.230100) plc reopen ok\n"
    "(100.300000) plc unit=1 fc=04 addr=0 count=2 rtt_us=40 exception=02\n"
    "(100.400000) plc unit=1 fc=04 addr=0 count=2 rtt_us=40 disconnected closed\n"
    "(100.400100) plc reopen failed\n"
    "(100.600000) plc reopen ok\n"
    "(100.600100) plc unit=1 fc=04 addr=0 count=2 rtt_us=50 ok 0005 0006\n"
    "(100.700000) plc unit=1 fc=04 addr=0 count=2 rtt_us=50 ok 0007 0008\n";

struct TraceFile {
  std::string path;
  explicit TraceFile(const std::string& text, const std::string& name = "plc.modbus.log") {
    const std::string dir = std::filesystem::temp_directory_path() / ("rise-mbreplay-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    path = dir + "/" + name;
    std::ofstream(path) << text;
  }
  ~TraceFile() { std::filesystem::remove(path); }
};

std::unique_ptr<ReplayModbusLink> replay(const TraceFile& file, const std::string& options) {
  return open_modbus_replay("replay://" + file.path + options);
}

// One request of the poll loop below and what it got.
struct Outcome {
  int64_t trace_us = 0;
  bool reopen = false;
  ModbusResult result;
  std::array<uint16_t, 2> registers{};
  int64_t took_us = 0;
  bool ended = false;
};

}  // namespace

TEST_CASE("a Modbus replay with fast=1 answers each read with its request's next recorded answer", "[hil_io]") {
  const TraceFile file(kTrace);
  const auto link = replay(file, "?fast=1");
  REQUIRE(link->is_open());
  std::array<uint16_t, 2> ir{};
  std::array<uint8_t, 2> coils{};
  std::array<uint16_t, 1> holding{};

  // A request the trace never holds: exception 02, as a slave without it.
  const ModbusResult unknown = link->read_holding_registers(0, holding);
  CHECK(unknown.status == ModbusStatus::Exception);
  CHECK(unknown.exception_code == 2);
  CHECK(link->unknown_requests() == 1);
  CHECK(link->read_input_registers(0, std::span<uint16_t>(ir.data(), 1)).status == ModbusStatus::Exception);

  REQUIRE(link->read_input_registers(0, ir).ok());
  CHECK(ir == std::array<uint16_t, 2>{1, 2});
  CHECK(link->last_request_trace_us() == kT0);
  REQUIRE(link->read_coils(3, coils).ok());
  CHECK(coils == std::array<uint8_t, 2>{1, 0});
  const std::array<uint8_t, 1> on{1};
  CHECK(link->write_coils(0, on).ok());
  CHECK(link->writes_dropped() == 1);
  REQUIRE(link->read_input_registers(0, ir).ok());
  CHECK(ir == std::array<uint16_t, 2>{3, 4});
  REQUIRE(link->read_coils(3, coils).ok());
  CHECK(coils == std::array<uint8_t, 2>{0, 1});

  // The timeout closed the link (a TCP restart): it reopens at once.
  const auto before = std::chrono::steady_clock::now();
  CHECK(link->read_input_registers(0, ir).status == ModbusStatus::Timeout);
  CHECK(std::chrono::steady_clock::now() - before < std::chrono::milliseconds(20));  // fast: no waiting
  CHECK_FALSE(link->is_open());
  CHECK(link->reopen() == ModbusStatus::Ok);
  const ModbusResult ex = link->read_input_registers(0, ir);
  CHECK(ex.status == ModbusStatus::Exception);
  CHECK(ex.exception_code == 2);

  // The slave went away at 100.4 and came back at 100.6.
  CHECK(link->read_input_registers(0, ir).status == ModbusStatus::Disconnected);
  CHECK_FALSE(link->is_open());
  CHECK(link->reopen() == ModbusStatus::Ok);  // fast: jumps to when it came back
  CHECK(link->last_request_trace_us() == kT0 + 600'000);
  REQUIRE(link->read_input_registers(0, ir).ok());
  CHECK(ir == std::array<uint16_t, 2>{5, 6});
  REQUIRE(link->read_input_registers(0, ir).ok());
  CHECK(ir == std::array<uint16_t, 2>{7, 8});

  // The end: closed, and it stays so.
  CHECK(link->read_input_registers(0, ir).status == ModbusStatus::Disconnected);
  CHECK(link->ended());
  CHECK_FALSE(link->is_open());
  CHECK(link->reopen() == ModbusStatus::Disconnected);
  CHECK(link->write_coils(0, on).status == ModbusStatus::Disconnected);
  CHECK(link->counters().reopens == 2);
}

TEST_CASE("a Modbus replay's window, loops and URL options", "[hil_io]") {
  const TraceFile file(kTrace);
  std::array<uint16_t, 2> ir{};
  SECTION("start= and stop= cut the window; the latest answer at the start stands") {
    const auto link = replay(file, "?fast=1&start=0.05&stop=0.35");
    CHECK(link->window().begin_us == kT0 + 50'000);
    CHECK(link->window().end_us == kT0 + 350'000);
    REQUIRE(link->read_input_registers(0, ir).ok());
    CHECK(ir == std::array<uint16_t, 2>{3, 4});
    CHECK(link->read_input_registers(0, ir).status == ModbusStatus::Timeout);
    link->reopen();
    CHECK(link->read_input_registers(0, ir).status == ModbusStatus::Exception);
    CHECK(link->read_input_registers(0, ir).status == ModbusStatus::Disconnected);
    CHECK(link->ended());
  }
  SECTION("loop=1 plays the window once more") {
    const auto link = replay(file, "?fast=1&start=0.6&loop=1");
    REQUIRE(link->read_input_registers(0, ir).ok());
    CHECK(ir == std::array<uint16_t, 2>{5, 6});
    REQUIRE(link->read_input_registers(0, ir).ok());
    CHECK(ir == std::array<uint16_t, 2>{7, 8});
    REQUIRE(link->read_input_registers(0, ir).ok());
    CHECK(ir == std::array<uint16_t, 2>{5, 6});  // the second pass
    REQUIRE(link->read_input_registers(0, ir).ok());
    CHECK(ir == std::array<uint16_t, 2>{7, 8});
    CHECK(link->read_input_registers(0, ir).status == ModbusStatus::Disconnected);
    CHECK(link->ended());
  }
  SECTION("the factory opens a replay for a Modbus source's replay:// URL") {
    const auto link = open_modbus_link("replay://" + file.path + "?speed=2");
    CHECK(dynamic_cast<ReplayModbusLink*>(link.get()) != nullptr);
  }
  SECTION("mistakes") {
    CHECK_THROWS_WITH(replay(file, "?ids=123"), Catch::Contains("ids=, channel= and step= are for CAN logs"));
    CHECK_THROWS_WITH(replay(file, "?step=1"), Catch::Contains("ids=, channel= and step= are for CAN logs"));
    CHECK_THROWS_WITH(replay(file, "?speed=0"), Catch::Contains("is not a number > 0"));
    CHECK_THROWS_WITH(replay(file, "?start=5"), Catch::Contains("is past the trace's end"));
    CHECK_THROWS_WITH(open_modbus_replay("replay:///nonexistent/x.modbus.log"),
                      "/nonexistent/x.modbus.log: cannot open: No such file or directory");
    const TraceFile can("(100.000000) can0 123#00\n", "console.log");
    CHECK_THROWS_WITH(replay(can, ""), Catch::Contains("not a Modbus trace"));
    const TraceFile two(std::string(kTrace) + "(100.800000) other unit=1 fc=04 addr=0 count=2 rtt_us=5 ok 0000 0000\n",
                        "two.modbus.log");
    CHECK_THROWS_WITH(replay(two, ""), Catch::Contains("two.modbus.log:16: the traffic of another source"));
    const TraceFile none("# rise-hild modbus trace v1\n(100.000000) plc link open\n", "none.modbus.log");
    CHECK_THROWS_WITH(replay(none, ""), Catch::Contains("no Modbus transaction to replay"));
  }
}

TEST_CASE("a Modbus replay in real time answers with the latest recorded answer at or before the replay time, "
          "is down where the recording was, and ends on time at any speed",
          "[hil_io]") {
  const double speed = GENERATE(1.0, 2.0);
  INFO("speed " << speed);
  const TraceFile file(kTrace);
  const auto link = replay(file, "?speed=" + std::to_string(speed));
  // A master's loop: poll every 10 ms (of the trace), reopen when closed.
  std::vector<Outcome> outcomes;
  const int64_t start = rise::msgs::monotonic_us();
  int64_t ended_after_us = -1;
  while (rise::msgs::monotonic_us() - start < 2'000'000) {
    Outcome o;
    const int64_t t = rise::msgs::monotonic_us();
    if (!link->is_open()) {
      o.reopen = true;
      o.result.status = link->reopen();
    } else {
      o.result = link->read_input_registers(0, o.registers);
    }
    o.took_us = rise::msgs::monotonic_us() - t;
    o.trace_us = link->last_request_trace_us();
    o.ended = link->ended();
    outcomes.push_back(o);
    if (link->ended()) {
      ended_after_us = rise::msgs::monotonic_us() - start;
      break;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(static_cast<int64_t>(10'000 / speed)));  // the poll period, not a sync
  }
  REQUIRE(ended_after_us > 0);
  // 0.70005 s of trace; the last request may come up to one poll late.
  CHECK(static_cast<double>(ended_after_us) == Approx(700'050 / speed).margin(10'000 / speed + 15'000));
  CHECK(link->reopen() == ModbusStatus::Disconnected);

  int timeouts = 0, disconnects = 0, failed_reopens = 0;
  for (const Outcome& o : outcomes) {
    const int64_t t = o.trace_us - kT0;
    INFO("trace time " << t << " µs, reopen " << o.reopen << ", " << to_string(o.result.status));
    if (o.ended) {
      CHECK(o.result.status == ModbusStatus::Disconnected);
    } else if (o.reopen) {
      // Down from the lost slave's answer (100.40004) until 100.6.
      const bool down = t >= 400'040 && t < 600'000;
      CHECK((o.result.status == ModbusStatus::Ok) == !down);
      failed_reopens += down;
    } else if (t < 100'000) {
      CHECK(o.registers == std::array<uint16_t, 2>{1, 2});
    } else if (t < 200'000) {
      CHECK(o.registers == std::array<uint16_t, 2>{3, 4});
    } else if (t < 300'000) {
      CHECK(o.result.status == ModbusStatus::Timeout);
      CHECK(o.took_us >= static_cast<int64_t>(30'000 / speed) - 1000);  // the recorded silence, at speed
      ++timeouts;
    } else if (t < 400'000) {
      CHECK(o.result.exception_code == 2);
    } else if (t < 600'000) {
      CHECK(o.result.status == ModbusStatus::Disconnected);
      ++disconnects;
    } else if (t < 700'000) {
      CHECK(o.registers == std::array<uint16_t, 2>{5, 6});
    } else {
      CHECK(o.registers == std::array<uint16_t, 2>{7, 8});
    }
  }
  CHECK(timeouts >= 1);
  CHECK(disconnects == 1);  // then closed: only reopens until the slave is back
  CHECK(failed_reopens >= 1);
}
