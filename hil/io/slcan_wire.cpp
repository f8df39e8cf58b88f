#include "hil/io/slcan_wire.hpp"

#include <algorithm>

namespace rise::hil::io {

namespace {

constexpr char kHex[] = "0123456789ABCDEF";

// Value of the hex digits of text; -1 when one is not a hex digit.
int64_t parse_hex(std::string_view text) {
  int64_t value = 0;
  for (const char c : text) {
    int digit;
    if (c >= '0' && c <= '9') {
      digit = c - '0';
    } else if (c >= 'A' && c <= 'F') {
      digit = c - 'A' + 10;
    } else if (c >= 'a' && c <= 'f') {
      digit = c - 'a' + 10;
    } else {
      return -1;
    }
    value = value * 16 + digit;
  }
  return value;
}

}  // namespace

std::optional<SlcanLine> parse_slcan_line(std::string_view line) {
  if (line.empty()) return std::nullopt;
  const char kind = line[0];
  if (kind != 't' && kind != 'T' && kind != 'r' && kind != 'R') return std::nullopt;
  const bool extended = kind == 'T' || kind == 'R';
  const bool remote = kind == 'r' || kind == 'R';
  const size_t id_digits = extended ? 8 : 3;
  if (line.size() < 1 + id_digits + 1) return std::nullopt;
  const int64_t id = parse_hex(line.substr(1, id_digits));
  const char dlc = line[1 + id_digits];
  if (id < 0 || id > (extended ? 0x1FFFFFFF : 0x7FF) || dlc < '0' || dlc > '8') return std::nullopt;
  const size_t len = static_cast<size_t>(dlc - '0');
  const size_t data_at = 2 + id_digits;
  const size_t stamp_at = data_at + (remote ? 0 : 2 * len);
  if (line.size() != stamp_at && line.size() != stamp_at + 4) return std::nullopt;
  SlcanLine out;
  out.frame.id = static_cast<uint32_t>(id);
  out.frame.extended = extended;
  out.frame.remote = remote;
  out.frame.len = static_cast<uint8_t>(len);
  for (size_t i = 0; i < (remote ? 0 : len); ++i) {
    const int64_t byte = parse_hex(line.substr(data_at + 2 * i, 2));
    if (byte < 0) return std::nullopt;
    out.frame.data[i] = static_cast<uint8_t>(byte);
  }
  if (line.size() == stamp_at + 4) {
    out.stamp_ms = parse_hex(line.substr(stamp_at, 4));
    if (out.stamp_ms < 0 || out.stamp_ms >= kSlcanStampWrapMs) return std::nullopt;
  }
  return out;
}

size_t format_slcan_line(const CanFrame& frame, SlcanLineBuffer& out) {
  size_t n = 0;
  out[n++] = '\r';
  out[n++] = frame.remote ? (frame.extended ? 'R' : 'r') : (frame.extended ? 'T' : 't');
  for (int shift = frame.extended ? 28 : 8; shift >= 0; shift -= 4) out[n++] = kHex[(frame.id >> shift) & 0xFu];
  // A classic frame holds up to 8 bytes; say so to the optimiser too.
  const size_t len = std::min<size_t>(frame.len, 8);
  out[n++] = static_cast<char>('0' + len);
  if (!frame.remote) {
    for (size_t i = 0; i < len; ++i) {
      out[n++] = kHex[frame.data[i] >> 4];
      out[n++] = kHex[frame.data[i] & 0xFu];
    }
  }
  out[n++] = '\r';
  return n;
}

}  // namespace rise::hil::io
