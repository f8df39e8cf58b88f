#pragma once

#include <array>
#include <cstdint>

namespace rise::hil::io {

/// One CAN or CAN FD frame as the transports carry it. Mirrors struct
/// canfd_frame of <linux/can.h> without depending on it, so code above the
/// transports compiles anywhere.
struct CanFrame {
  uint32_t id = 0;          ///< 11-bit or 29-bit identifier, no flag bits
  bool extended = false;    ///< 29-bit identifier (CAN_EFF_FLAG)
  bool remote = false;      ///< remote transmission request (CAN_RTR_FLAG)
  bool error = false;       ///< error frame (CAN_ERR_FLAG); id holds the error class
  bool fd = false;          ///< CAN FD frame (up to 64 data bytes)
  bool brs = false;         ///< CAN FD bit-rate switch
  bool esi = false;         ///< CAN FD error state indicator
  uint8_t len = 0;          ///< data length in bytes (0..8, or 0..64 for FD)
  std::array<uint8_t, 64> data{};
  int64_t timestamp_us = 0; ///< receive time, microseconds since the Unix epoch; 0 if unknown
};

/// True when len is a length a CAN FD frame can have (ISO 11898-1 DLC table:
/// 0..8, 12, 16, 20, 24, 32, 48, 64). Safe in the cyclic path.
bool is_fd_length(unsigned len);

/// True when a bus can carry the frame: the id fits its format (11 or 29
/// bits; error class for error frames), len is 0..8 for classic frames and
/// an FD length for FD frames, BRS/ESI only on FD frames, no remote FD
/// frames. Safe in the cyclic path.
bool is_well_formed(const CanFrame& frame);

/// True when both frames carry the same id, flags, length and payload bytes
/// (bytes past len and the timestamp are ignored). Safe in the cyclic path.
bool same_content(const CanFrame& a, const CanFrame& b);

}  // namespace rise::hil::io
