#pragma once

// The binary CAN log formats behind CanLogReader (internal to hil/io):
//   Vector BLF          "LOGG" header, zlib'd LOG_CONTAINERs of LOBJ objects,
//                       read as python-can's can/io/blf.py documents them;
//   pcap and pcapng     SocketCAN captures (link type 227, or Linux cooked
//                       SLL/SLL2 carrying CAN), through Debian's libpcap.

#include <cstdint>
#include <memory>
#include <string>

#include "hil/io/can_log.hpp"

namespace rise::hil::io {

class BinaryCanLog {
 public:
  enum class Result { Frame, Malformed, End };
  virtual ~BinaryCanLog() = default;
  /// The next frame, or one malformed object (record.line names it), or the
  /// end. Never throws.
  virtual Result next(CanLogRecord& record) = 0;
  virtual void rewind() = 0;
  virtual uint64_t bytes_consumed() const = 0;
};

/// The binary reader for path when its first bytes are a BLF or pcap/pcapng
/// magic (format set accordingly), nullptr when they are not. Throws
/// std::runtime_error naming the path when the file is one but cannot be
/// opened (libpcap's message, an unsupported link type).
std::unique_ptr<BinaryCanLog> open_binary_can_log(const std::string& path, CanLogFormat& format);

}  // namespace rise::hil::io
