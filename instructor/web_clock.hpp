#pragma once

// The web console's clocks: monotonic microseconds for the virtual panels'
// timeouts and the publisher watch, wall-clock microseconds for utime.

#include <chrono>
#include <cstdint>

namespace rise::instructor {

inline int64_t monotonic_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}
inline int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace rise::instructor
