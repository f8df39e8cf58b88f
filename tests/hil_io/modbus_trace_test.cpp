// The Modbus transaction trace: its lines round-trip, every mistake is
// named, and a RecordingModbusLink in front of a real libmodbus TCP pair
// writes what went over the wire.

#include <catch2/catch.hpp>

#include <unistd.h>

#include <array>
#include <filesystem>
#include <fstream>

#include "hil/io/modbus_server.hpp"
#include "hil/io/modbus_trace.hpp"
#include "hil/io/recording_modbus_link.hpp"
#include "tests/hil_io/test_support.hpp"

using namespace rise::hil::io;

namespace {
std::string temp_dir(const std::string& name) {
  const std::string dir = std::filesystem::temp_directory_path() / (name + "-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}
}  // namespace

TEST_CASE("modbus trace lines read back as they were written", "[hil_io]") {
  const std::string line = GENERATE(as<std::string>{},
      "(1700000000.001234) console unit=1 fc=04 addr=0 count=3 rtt_us=412 ok 0000 3333 FFFF",
      "(1700000000.001700) console unit=1 fc=02 addr=0 count=8 rtt_us=288 ok 10000001",
      "(1700000000.001800) plc unit=3 fc=01 addr=8 count=3 rtt_us=120 ok 011",
      "(1700000000.001900) plc unit=3 fc=03 addr=3 count=2 rtt_us=130 ok 0002 FE0C",
      "(1700000000.011234) console unit=1 fc=15 addr=0 count=4 rtt_us=301 ok 1010",
      "(1700000000.011600) console unit=17 fc=16 addr=100 count=2 rtt_us=350 ok 0000 002A",
      "(1700000000.021234) console unit=1 fc=04 addr=0 count=18 rtt_us=100087 timeout closed",
      "(1700000000.031234) console unit=1 fc=04 addr=100 count=1 rtt_us=390 exception=02",
      "(1700000000.041234) panel unit=1 fc=02 addr=0 count=32 rtt_us=5 crc",
      "(1700000000.051234) console unit=1 fc=16 addr=0 count=1 rtt_us=9 disconnected closed 0001",
      "(1700000000.000000) console link open", "(1700000000.000000) console link closed",
      "(1700000000.021400) console reopen ok", "(1700000000.021400) console reopen failed",
      "(1700000000.021400) console close");
  const ModbusTraceParse p = parse_modbus_trace_line(line + "\r\n");
  INFO(p.error);
  REQUIRE(p.ok);
  CHECK(format_modbus_trace_line(p.record) == line);
}

TEST_CASE("a modbus trace line's fields mean what the format says", "[hil_io]") {
  const auto p = parse_modbus_trace_line(
      "(1700000000.001234) console unit=1 fc=04 addr=2 count=3 rtt_us=412 ok 0000 3333 FFFF");
  REQUIRE(p.ok);
  const ModbusTraceRecord& r = p.record;
  CHECK(r.kind == ModbusTraceRecord::Kind::Transaction);
  CHECK(r.time_us == 1'700'000'000'001'234);
  CHECK(r.answer_us() == 1'700'000'000'001'646);
  CHECK(r.source == "console");
  CHECK(r.function == ModbusFunction::ReadInputRegisters);
  CHECK(r.address == 2);
  CHECK(r.values == std::vector<uint16_t>{0x0000, 0x3333, 0xFFFF});
  const auto e = parse_modbus_trace_line("(1.5) c unit=1 fc=04 addr=100 count=1 rtt_us=390 exception=0B closed");
  REQUIRE(e.ok);
  CHECK(e.record.result.status == ModbusStatus::Exception);
  CHECK(e.record.result.exception_code == 0x0B);
  CHECK(e.record.closed);
  CHECK(e.record.values.empty());
  CHECK(parse_modbus_trace_line("# a comment").skip);
  CHECK(parse_modbus_trace_line("   ").skip);
}

TEST_CASE("a malformed modbus trace line is refused with what is wrong", "[hil_io]") {
  const auto [line, error] = GENERATE(table<std::string, std::string>({
      {"console unit=1 fc=04 addr=0 count=1 rtt_us=1 ok 0000", "no (seconds.micros) time"},
      {"(1.0) console", "no source and event"},
      {"(1.0) console link maybe", "expected 'link open' or 'link closed'"},
      {"(1.0) console unit=1 fc=05 addr=0 count=1 rtt_us=1 ok 0000", "bad fc= field 'fc=05' (01, 02, 03, 04, 15 or 16)"},
      {"(1.0) console unit=1 fc=04 addr=x count=1 rtt_us=1 ok 0000", "bad addr= field"},
      {"(1.0) console unit=1 fc=04 addr=0 count=2 rtt_us=1 ok 0000", "count=2 but 1 registers"},
      {"(1.0) console unit=1 fc=04 addr=0 count=1 rtt_us=1 ok 00000", "is not four hex digits"},
      {"(1.0) console unit=1 fc=02 addr=0 count=4 rtt_us=1 ok 101", "count=4 but 3 bits"},
      {"(1.0) console unit=1 fc=02 addr=0 count=3 rtt_us=1 ok 102", "bit '2' is not 0 or 1"},
      {"(1.0) console unit=1 fc=04 addr=0 count=1 rtt_us=1 maybe", "bad result 'maybe'"},
      {"(1.0) console unit=1 fc=04 addr=0 count=1 rtt_us=1 timeout 0000", "unexpected '0000'"},
      {"(1.0) console unit=1 fc=04 addr=0 count=1", "a transaction needs"},
  }));
  const ModbusTraceParse p = parse_modbus_trace_line(line);
  CHECK_FALSE(p.ok);
  CHECK_FALSE(p.skip);
  CHECK_THAT(p.error, Catch::Contains(error));
}

TEST_CASE("a modbus trace file with a bad line is refused with its path and line", "[hil_io]") {
  const std::string dir = temp_dir("rise-mbtrace");
  const std::string path = dir + "/console.modbus.log";
  {
    std::ofstream out(path);
    out << "# rise-hild modbus trace v1\n(1.0) console link open\n"
        << "(1.1) console unit=1 fc=04 addr=0 count=1 rtt_us=1 ok 0000 0001\n";
  }
  CHECK(looks_like_modbus_trace(path));
  ModbusTraceReader reader(path);
  ModbusTraceRecord r;
  REQUIRE(reader.next(r));
  CHECK(r.kind == ModbusTraceRecord::Kind::Link);
  CHECK(r.line == 2);
  CHECK_THROWS_WITH(reader.next(r), path + ":3: count=1 but 2 registers");
  CHECK_THROWS_WITH(ModbusTraceReader(dir + "/absent.modbus.log"),
                    dir + "/absent.modbus.log: cannot open: No such file or directory");
  std::filesystem::remove_all(dir);
}

TEST_CASE("a recorded modbus link writes every request with its answer, timing and the link's reopens", "[hil_io]") {
  ModbusServer server("modbus+tcp-listen://127.0.0.1:0?unit=1", ModbusTableSizes{});
  std::array<uint16_t, 18> regs{};
  for (std::size_t i = 0; i < regs.size(); ++i) regs[i] = static_cast<uint16_t>(0x1000 + i);
  server.set_inputs(regs, 0x80000005u);
  const std::string dir = temp_dir("rise-mbrec");
  const std::string path = dir + "/console.modbus.log";
  const std::string url = "modbus+tcp://127.0.0.1:" + std::to_string(server.port()) + "?unit=1&timeout_ms=200";
  {
    RecordingModbusLink link(open_modbus_link(url), path, "console", 1);
    REQUIRE(link.is_open());
    std::array<uint16_t, 18> got{};
    std::array<uint8_t, 32> bits{};
    CHECK(link.read_input_registers(0, got).ok());
    CHECK(got == regs);
    CHECK(link.read_discrete_inputs(0, bits).ok());
    const std::array<uint8_t, 4> coils{1, 0, 1, 1};
    CHECK(link.write_coils(0, coils).ok());
    const std::array<uint16_t, 2> holding{7, 0xBEEF};
    CHECK(link.write_registers(3, holding).ok());
    std::array<uint16_t, 1> beyond{};
    const ModbusResult ex = link.read_input_registers(500, beyond);  // past the map: ILLEGAL DATA ADDRESS
    CHECK(ex.status == ModbusStatus::Exception);
    CHECK(link.reopen() == ModbusStatus::Ok);
    CHECK(link.counters().requests == 5);
    CHECK(link.counters().exceptions == 1);
    CHECK(link.lines_recorded() == 8);  // the header, the link state, 5 requests, the reopen
    CHECK(link.write_errors() == 0);
  }
  std::vector<ModbusTraceRecord> records;
  ModbusTraceReader reader(path);
  for (ModbusTraceRecord r; reader.next(r);) records.push_back(r);
  REQUIRE(records.size() == 7);
  CHECK(records[0].kind == ModbusTraceRecord::Kind::Link);
  CHECK(records[0].open);
  CHECK(records[1].function == ModbusFunction::ReadInputRegisters);
  CHECK(records[1].values == std::vector<uint16_t>(regs.begin(), regs.end()));
  CHECK(records[1].unit == 1);
  CHECK(records[1].rtt_us > 0);
  CHECK(records[1].rtt_us < 200'000);
  std::vector<uint16_t> di(32, 0);
  di[0] = di[2] = di[31] = 1;
  CHECK(records[2].values == di);
  CHECK(records[3].function == ModbusFunction::WriteMultipleCoils);
  CHECK(records[3].values == std::vector<uint16_t>{1, 0, 1, 1});
  CHECK(records[4].address == 3);
  CHECK(records[4].values == std::vector<uint16_t>{7, 0xBEEF});
  CHECK(records[5].result.status == ModbusStatus::Exception);
  CHECK(records[5].result.exception_code == 0x02);
  CHECK(records[5].address == 500);
  CHECK(records[6].kind == ModbusTraceRecord::Kind::Reopen);
  CHECK(records[6].open);
  for (std::size_t i = 1; i < records.size(); ++i) CHECK(records[i].time_us >= records[i - 1].time_us);
  std::filesystem::remove_all(dir);
}

TEST_CASE("a recorded modbus link reads a device's coils and holding registers with functions 01 and 03",
          "[hil_io]") {
  ModbusServer server("modbus+tcp-listen://127.0.0.1:0?unit=1", ModbusTableSizes{});
  server.set_coils(2, std::array<uint8_t, 3>{1, 0, 1});
  server.set_holding_registers(3, std::array<uint16_t, 2>{2, 0xFE0C});
  const std::string dir = temp_dir("rise-mbrec03");
  const std::string path = dir + "/plc.modbus.log";
  const std::string url = "modbus+tcp://127.0.0.1:" + std::to_string(server.port()) + "?unit=1&timeout_ms=200";
  {
    RecordingModbusLink link(open_modbus_link(url), path, "plc", 1);
    std::array<uint8_t, 3> coils{};
    std::array<uint16_t, 2> holding{};
    REQUIRE(link.read_coils(2, coils).ok());
    CHECK(coils == std::array<uint8_t, 3>{1, 0, 1});
    REQUIRE(link.read_holding_registers(3, holding).ok());
    CHECK(holding == std::array<uint16_t, 2>{2, 0xFE0C});
  }
  std::vector<ModbusTraceRecord> records;
  ModbusTraceReader reader(path);
  for (ModbusTraceRecord r; reader.next(r);) records.push_back(r);
  REQUIRE(records.size() == 3);
  CHECK(records[1].function == ModbusFunction::ReadCoils);
  CHECK(records[1].address == 2);
  CHECK(records[1].values == std::vector<uint16_t>{1, 0, 1});
  CHECK(records[2].function == ModbusFunction::ReadHoldingRegisters);
  CHECK(records[2].values == std::vector<uint16_t>{2, 0xFE0C});
  CHECK(format_modbus_trace_line(records[2]).find(" fc=03 addr=3 count=2 ") != std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST_CASE("a recorder whose disk is full counts the lost lines and passes the traffic on", "[hil_io]") {
  ModbusServer server("modbus+tcp-listen://127.0.0.1:0?unit=1", ModbusTableSizes{});
  const std::string url = "modbus+tcp://127.0.0.1:" + std::to_string(server.port()) + "?unit=1&timeout_ms=200";
  RecordingModbusLink link(open_modbus_link(url), "/dev/full", "console", 1);
  std::array<uint16_t, 18> got{};
  // Lines are flushed every 100 ms; the first flush onto /dev/full fails.
  CHECK(test::wait_until([&] {
    CHECK(link.read_input_registers(0, got).ok());
    return link.write_errors() > 0;
  }));
}
