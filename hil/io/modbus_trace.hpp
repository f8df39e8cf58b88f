#pragma once

// A Modbus master's traffic as a text trace: one line per request with its
// answer, in the spirit of candump's log (a time in parentheses, then the
// source, then what happened), so that grep, awk and a replay read it alike.
//
//   # rise-hild modbus trace v1
//   (1700000000.000000) console link open
//   (1700000000.001234) console unit=1 fc=04 addr=0 count=18 rtt_us=66 ok C000 6666 0000 0000 0000 0000 0000 0001
//                       0000 0000 0000 0000 0001 0001 0000 0258 003D 3419   (one line in the file)
//   (1700000000.001700) console unit=1 fc=02 addr=0 count=32 rtt_us=288 ok 10000000000000000000000000000000
//   (1700000000.011234) console unit=1 fc=15 addr=0 count=8 rtt_us=301 ok 10100000
//   (1700000000.011600) console unit=1 fc=16 addr=0 count=25 rtt_us=350 ok 0000 0002 0000 002A 0000 ...
//   (1700000000.021234) console unit=1 fc=04 addr=0 count=18 rtt_us=100087 timeout closed
//   (1700000000.021400) console reopen ok
//   (1700000000.031234) console unit=1 fc=04 addr=100 count=1 rtt_us=390 exception=02
//
// The time is when the request went out (wall clock, µs since the Unix
// epoch); rtt_us is how long the answer (or the timeout) took. fc is the
// Modbus function code in decimal, two digits: 01 read coils, 02 read
// discrete inputs, 03 read holding registers, 04 read input registers, 15
// write multiple coils, 16 write multiple registers (01 and 03 are what a
// protocol "modbus" source polls besides 02 and 04). The result is ok, timeout, exception=CC (the slave's exception
// code, hex), crc (an RTU frame with a bad CRC), disconnected or error;
// "closed" follows when the request left the link closed (a TCP timeout, a
// broken connection). Values: registers as four hex digits each, bits as one
// 0/1 per address (first address first); reads carry the values read (ok
// only), writes the values written. Other lines: "link open" / "link
// closed" (the state when recording began), "reopen ok" / "reopen failed",
// "close". Lines starting with '#' are comments.
//
// Worked example (the values of a poll in tests/data/replay/modbus/console.modbus.log): a
// poll of the console's 18 input registers (rise-modbus-v1,
// firmware_protocol/console_modbus.hpp) answered in 66 µs: axis.0 = 0xC000
// (-16384, drive_x -0.5), axis.1 = 0x6666 (26214, drive_y 0.8), axes 2..5 = 0,
// switch.0 = 0, switch.1 = 1 (speed medium), switches 2..5 = 0, status 1
// (operational), version 1, uptime 0x00000258 = 600 ms, alive counter 0x003D,
// CRC-16/MODBUS of registers 0..16 = 0x3419; the fc=02 line after it reads
// button.0 (the dead-man) held.
// `grep ' fc=04 .* timeout'` lists the polls that went unanswered.

#include <cstdint>
#include <fstream>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "hil/io/modbus_link.hpp"

namespace rise::hil::io {

/// Function codes the trace knows (Modbus Application Protocol V1.1b3 §6).
enum class ModbusFunction : uint8_t {
  ReadCoils = 1,
  ReadDiscreteInputs = 2,
  ReadHoldingRegisters = 3,
  ReadInputRegisters = 4,
  WriteMultipleCoils = 15,
  WriteMultipleRegisters = 16,
};
/// True for the functions whose values are bits (01, 02, 15).
bool is_bit_function(ModbusFunction function);

struct ModbusTraceRecord {
  enum class Kind { Transaction, Link, Reopen, Close };
  Kind kind = Kind::Transaction;
  int64_t time_us = 0;   ///< request time (µs since the epoch)
  std::string source;
  // Transaction:
  int unit = 0;
  ModbusFunction function = ModbusFunction::ReadInputRegisters;
  uint16_t address = 0;
  uint16_t count = 0;
  int64_t rtt_us = 0;
  ModbusResult result;
  bool closed = false;            ///< the link was closed after it
  std::vector<uint16_t> values;   ///< registers, or bits as 0/1; empty for a failed read
  // Link (state when recording began) and Reopen (its outcome):
  bool open = false;
  int line = 0;  ///< 1-based line number in the file
  /// When the answer came: time_us + rtt_us.
  int64_t answer_us() const { return time_us + rtt_us; }
};

/// Appends one transaction line (no newline). `values` are registers for 03,
/// 04 and 16, bits (0/1) for 01, 02 and 15. Allocates nothing when `out` has the
/// room (about 40 + 5 per register bytes plus the source name); no throw then.
void append_modbus_transaction(std::string& out, int64_t time_us, std::string_view source, int unit,
                               ModbusFunction function, uint16_t address, uint16_t count, int64_t rtt_us,
                               const ModbusResult& result, bool closed, std::span<const uint16_t> values);
void append_modbus_transaction(std::string& out, int64_t time_us, std::string_view source, int unit,
                               ModbusFunction function, uint16_t address, uint16_t count, int64_t rtt_us,
                               const ModbusResult& result, bool closed, std::span<const uint8_t> bits);
/// Appends "link open" / "reopen failed" / "close" lines.
void append_modbus_event(std::string& out, int64_t time_us, std::string_view source, ModbusTraceRecord::Kind kind,
                         bool open);

/// One line as text (no newline), for tests and tools.
std::string format_modbus_trace_line(const ModbusTraceRecord& record);

struct ModbusTraceParse {
  bool ok = false;
  bool skip = false;     ///< a comment or an empty line
  std::string error;     ///< what is wrong, e.g. "count=12 but 11 values"
  ModbusTraceRecord record;
};
/// Parses one line. Does not throw.
ModbusTraceParse parse_modbus_trace_line(std::string_view line);

/// Reads a trace file line by line.
class ModbusTraceReader {
 public:
  /// Throws std::runtime_error naming the path when it cannot be opened.
  explicit ModbusTraceReader(const std::string& path);
  /// The next record; false at the end. Throws std::runtime_error
  /// "path:line: what" for a line that is not a trace line (as a config
  /// file's loader does: a trace is input to a tool, not the cyclic path).
  bool next(ModbusTraceRecord& record);
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::ifstream in_;
  std::string text_;
  int line_ = 0;
};

/// True when the file's first non-empty line is a Modbus trace line or its header.
bool looks_like_modbus_trace(const std::string& path);

}  // namespace rise::hil::io
