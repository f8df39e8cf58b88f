#pragma once

// candump's log format (`candump -l`, read by canplayer and python-can):
//   (1436509052.249713) can0 123#DEADBEEF        classic, 11-bit id
//   (1436509052.249713) can0 12345678#00         29-bit id (8 hex digits)
//   (1436509052.249713) can0 123#R  / 123#R4     remote frame (with length)
//   (1436509052.249713) can0 123##1112233        CAN FD: flags nibble, then data
//   (1436509052.249713) can0 20000080#0000...    error frame (CAN_ERR_FLAG in the id)
//   (1436509052.249713) can0 123#DEADBEEF T      direction after the frame: R received,
//                                                T sent (candump -x, python-can's writer)
// as can-utils' lib.c (parse_canframe, sprint_canframe) reads and writes it.

#include <optional>
#include <string>
#include <string_view>

#include "hil/io/can_frame.hpp"

namespace rise::hil::io {

struct CandumpRecord {
  CanFrame frame;          ///< frame.timestamp_us holds the log's time
  std::string interface;   ///< e.g. "can0"
  bool tx = false;         ///< the line ends in " T": the logging node sent the frame
};

/// Whether a written line says which way the frame went.
enum class CandumpDirection { None, Received, Sent };

enum class CandumpError { None, Empty, NoTimestamp, NoInterface, BadId, BadData, TooLong };
const char* to_string(CandumpError error);

struct CandumpParse {
  CandumpError error = CandumpError::None;
  CandumpRecord record;
  bool ok() const { return error == CandumpError::None; }
};

/// Reads the "(seconds.micros)" that starts a candump line (and a Modbus
/// trace line, modbus_trace.hpp) as microseconds since the epoch; `rest`
/// gets what follows it. nullopt when the line does not start with one.
/// Does not throw.
std::optional<int64_t> parse_log_time(std::string_view line, std::string_view* rest);
/// Appends "(seconds.micros)", e.g. "(1700000000.000001)". Allocates
/// nothing when `out` has the room.
void append_log_time(std::string& out, int64_t time_us);
/// A capture's packet time (seconds and microseconds, as libpcap gives it)
/// in microseconds, or nullopt when no log line can carry it: before 1970,
/// more than 12 digits of seconds, or microseconds outside 0..999999 (a
/// classic pcap stores them unchecked; a pcapng's 64-bit stamp can be anything).
std::optional<int64_t> capture_time_us(int64_t seconds, int64_t micros);

/// Parses one log line (trailing "\r\n" and comments after the frame are
/// ignored). Does not throw.
CandumpParse parse_candump_line(std::string_view line);

/// The same without allocating: fills `frame` (every field) and points
/// `interface` into `line`. Safe in the cyclic path.
CandumpError parse_candump_line(std::string_view line, CanFrame& frame, std::string_view& interface,
                                bool* tx = nullptr);

/// Fast path for the common shape of a candump line, as candump -l (and our
/// recorder) writes classic frames: "(SEC.USEC) IFACE ID#HEXDATA[ R| T]"
/// with 6 digits of microseconds, a 3- or 8-digit id and whole data bytes,
/// ended by "\n" (or "\r\n") before `end`. Returns the position after the newline with
/// `frame` and `interface` filled exactly as parse_candump_line would, or
/// nullptr (nothing consumed) for any other line: the caller then takes the
/// general parser. Safe in the cyclic path.
const char* parse_candump_fast(const char* p, const char* end, CanFrame& frame, std::string_view& interface,
                               bool& tx);

/// Writes one frame as a log line (without newline), e.g.
/// "(1700000000.000001) can0 123#DEADBEEF", with " R" or " T" appended
/// when a direction is given.
std::string format_candump_line(const CanFrame& frame, std::string_view interface,
                                CandumpDirection direction = CandumpDirection::None);
/// The same line appended to `out` (no newline): allocates nothing once
/// `out` has the capacity (about 170 bytes plus the interface name), so a
/// recorder can reuse one buffer in the cyclic path. Does not throw then.
void append_candump_line(std::string& out, const CanFrame& frame, std::string_view interface,
                         CandumpDirection direction = CandumpDirection::None);

}  // namespace rise::hil::io
