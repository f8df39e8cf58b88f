#pragma once

// The slcan line protocol without the tty (slcan_bus.hpp holds the adapter):
// a frame as the adapter sends it and as it is sent to the adapter.
// Wire format (Lawicel CANUSB manual; the CANable slcan firmware and Linux's
// drivers/net/can/slcan agree). Every command and every received frame ends
// with '\r'; the adapter answers a command with '\r' (OK) or '\a' (BELL).
//   id 0x123, bytes 11 22 33        → "t1233112233\r"
//   id 0x1ABCDEF0 (29 bit), DE AD   → "T1ABCDEF02DEAD\r"
//   remote id 0x321, length 2       → "r3212\r"      ("R" + 8 digits for 29 bit)
//   with Z1, 8000 ms adapter time   → "t12331122331F40\r"  (ms, wraps at 60000)

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "hil/io/can_frame.hpp"

namespace rise::hil::io {

/// The adapter's time stamps wrap at this many milliseconds.
constexpr int64_t kSlcanStampWrapMs = 60'000;

/// One received frame line: the frame (timestamp_us not set) and the
/// adapter's time stamp in ms, -1 when the line has none.
struct SlcanLine {
  CanFrame frame;
  int64_t stamp_ms = -1;
};

/// Parses one line without its '\r' (t, T, r or R, id, length, data, an
/// optional 4-digit stamp below kSlcanStampWrapMs). nullopt when it is not
/// such a line. No allocation, no throw.
std::optional<SlcanLine> parse_slcan_line(std::string_view line);

/// Room for "\r" + the longest frame line + "\r".
using SlcanLineBuffer = std::array<char, 1 + 1 + 8 + 1 + 16 + 1>;

/// Writes the frame's line, ending in '\r', to out from index 1 (out[0] is a
/// '\r' that ends a line an earlier timeout cut); returns the end index.
/// The frame must be classic, well formed and not an error frame.
size_t format_slcan_line(const CanFrame& frame, SlcanLineBuffer& out);

}  // namespace rise::hil::io
