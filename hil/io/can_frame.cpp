#include "hil/io/can_frame.hpp"

#include <algorithm>

namespace rise::hil::io {

namespace {

constexpr uint32_t kStandardIdMax = 0x7FF;      // CAN_SFF_MASK
constexpr uint32_t kExtendedIdMax = 0x1FFFFFFF;  // CAN_EFF_MASK, also CAN_ERR_MASK
constexpr unsigned kClassicMaxLen = 8;

}  // namespace

bool is_fd_length(unsigned len) {
  if (len <= 8) return true;
  switch (len) {
    case 12: case 16: case 20: case 24: case 32: case 48: case 64:
      return true;
    default:
      return false;
  }
}

bool is_well_formed(const CanFrame& frame) {
  if (frame.error) {
    // Error frames are classic frames whose id is the error class (linux/can/error.h).
    return !frame.fd && !frame.remote && frame.id <= kExtendedIdMax &&
           frame.len <= kClassicMaxLen;
  }
  if (frame.id > (frame.extended ? kExtendedIdMax : kStandardIdMax)) return false;
  if (frame.fd) return !frame.remote && is_fd_length(frame.len);
  return !frame.brs && !frame.esi && frame.len <= kClassicMaxLen;
}

bool same_content(const CanFrame& a, const CanFrame& b) {
  if (a.id != b.id || a.extended != b.extended || a.remote != b.remote || a.error != b.error ||
      a.fd != b.fd || a.brs != b.brs || a.esi != b.esi || a.len != b.len) {
    return false;
  }
  if (a.remote) return true;  // a remote request carries a length but no bytes
  const size_t n = std::min<size_t>(a.len, a.data.size());
  return std::equal(a.data.begin(), a.data.begin() + static_cast<std::ptrdiff_t>(n), b.data.begin());
}

}  // namespace rise::hil::io
