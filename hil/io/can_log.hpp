#pragma once

// One streaming reader for the CAN log formats met in practice:
//   candump -l   (1398128223.803317) can0 166#D0320009          (see candump_log.hpp)
//   Vector ASC      17.876708 1  6F9  Rx   d 8 05 0C 00 00 00 00 00 00
//                   30.005021 CANFD   1 Rx  300  1 0 8  8 11 c2 03 04 05 06 07 08 ...
//   PEAK TRC 2.x        2     17876.708 DT 1      06F9 Rx -  8    05 0C 00 00 00 00 00 00
//   PEAK TRC 1.x        1)      1841.0  Rx         0001  8  00 00 00 00 00 00 00 00
//   Vector BLF      binary: zlib'd containers of CAN, CAN FD and error objects
//   pcap, pcapng    SocketCAN captures (tcpdump, Wireshark, candump to pcap):
//                   link type 227, or Linux cooked SLL/SLL2 carrying CAN
// The binary formats are told by their first bytes (see can_log_binary.hpp).

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "hil/io/can_frame.hpp"

namespace rise::hil::io {

enum class CanLogFormat { Candump, VectorAsc, PeakTrc, VectorBlf, Pcap, Pcapng };
const char* to_string(CanLogFormat format);

/// One frame of a log. frame.timestamp_us is the file's time as the file
/// counts it: seconds since the Unix epoch for candump, since the start of
/// the measurement for ASC and TRC (relative ASC stamps are summed up),
/// since the Unix epoch for pcap/pcapng and for BLF (its header's start
/// time, local time taken as UTC, plus each object's offset; the offset
/// alone when the header has no start time).
/// Error frames carry no error class in ASC/TRC/BLF: their id is 0 and len 8.
struct CanLogRecord {
  CanFrame frame;
  std::string channel;  ///< "can0" (candump), "1" (ASC, TRC bus); empty if the file has none
  int line = 0;         ///< 1-based line number in the file (object or packet number in BLF, pcap)
  bool tx = false;      ///< the logger sent it (ASC/TRC "Tx", candump " T")
};

/// Reads a log file record by record (a block of lines in memory at a time).
/// Lines that are neither a frame nor a known non-frame line (header,
/// comment, statistics, chip status, J1939 transport summary, TRC status)
/// are counted as malformed and skipped; next() never throws.
class BinaryCanLog;

class CanLogReader {
 public:
  /// How many malformed line numbers are kept (the count goes on).
  static constexpr size_t kMaxMalformedLines = 1000;

  /// Opens path and detects its format from its first bytes (BLF, pcap,
  /// pcapng), the first lines, then the extension (.log .asc .trc). Throws
  /// std::runtime_error naming the path when it cannot be opened or its
  /// format is not recognised.
  explicit CanLogReader(const std::string& path);
  ~CanLogReader();
  CanLogReader(CanLogReader&&) noexcept;
  CanLogReader& operator=(CanLogReader&&) noexcept;

  /// The next frame record; false at the end of the file. Does not throw;
  /// allocates only for the channel string and long lines.
  bool next(CanLogRecord& record);

  /// Goes back to the first line; the malformed count starts again.
  void rewind();

  CanLogFormat format() const { return format_; }
  /// Bytes of the file consumed so far in this pass, and its size (progress).
  uint64_t bytes_consumed() const;
  uint64_t size_bytes() const { return size_bytes_; }
  const std::string& path() const { return path_; }
  /// Malformed lines (objects, packets) seen so far and the first kMaxMalformedLines of their numbers.
  size_t malformed_count() const { return malformed_count_; }
  const std::vector<int>& malformed_lines() const { return malformed_lines_; }

 private:
  enum class LineResult { Frame, Skip, Malformed };
  LineResult parse_line(std::string_view line, CanLogRecord& record);
  LineResult parse_asc(std::string_view line, CanLogRecord& record);
  LineResult parse_trc(std::string_view line, CanLogRecord& record);
  void reset_state();

  // The file is read in large blocks, lines are views into them (the
  // remainder of a block carried to the next): no copy per line.
  bool next_line(std::string_view& line);

  void count_malformed(int line);

  std::string path_;
  std::unique_ptr<BinaryCanLog> binary_;  // BLF, pcap, pcapng; null for the text formats
  std::ifstream in_;
  std::vector<char> block_;
  std::size_t block_begin_ = 0;  // first unread byte in block_
  std::size_t block_end_ = 0;    // end of valid bytes in block_
  bool eof_ = false;
  uint64_t stream_read_ = 0;  // bytes read from the file in this pass
  uint64_t size_bytes_ = 0;
  CanLogFormat format_ = CanLogFormat::Candump;
  int line_ = 0;
  size_t malformed_count_ = 0;
  std::vector<int> malformed_lines_;
  // ASC header state.
  bool asc_decimal_ = false;
  bool asc_relative_ = false;
  int64_t asc_last_us_ = 0;
  // TRC header state: version times 10 (11 = 1.1, 21 = 2.1), column letters.
  int trc_version_ = 0;
  std::string trc_columns_;
};

/// Every record of a file (convenience for tests and tools; not for big files
/// in the cyclic path). Throws as CanLogReader's constructor.
std::vector<CanLogRecord> read_can_log(const std::string& path);

}  // namespace rise::hil::io
