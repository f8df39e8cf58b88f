#pragma once

// The two clocks of the project: wall-clock microseconds stamp messages
// (`utime`, LCM's convention: since the Unix epoch, comparable between
// machines), steady microseconds time periods, timeouts and staleness
// (never jumps when NTP steps the wall clock).

#include <chrono>
#include <cstdint>

namespace rise::msgs {

inline int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

inline int64_t monotonic_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace rise::msgs
