#pragma once

// Small POSIX helpers shared by the transports of this folder (not an API
// for code above hil/io).

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <string>

#include "hil/io/can_bus.hpp"

namespace rise::hil::io::detail {

using Clock = std::chrono::steady_clock;

/// Milliseconds left until deadline, never negative.
int remaining_ms(Clock::time_point deadline);

/// Text for an errno value; thread-safe, no allocation.
const char* errno_text(int err);

/// Closes fd if open and sets it to -1.
void close_fd(int& fd);

/// Waits until fd is ready for events (POLLIN/POLLOUT) or until timeout_ms
/// passed. Ok when ready (also on POLLERR/POLLHUP: the next call reports
/// them), Timeout, or Error with errno set. Restarts after EINTR.
IoStatus wait_fd(int fd, short events, int timeout_ms);

/// Writes all of data to a non-blocking stream socket, waiting up to
/// timeout_ms for buffer space. written says how much went out, so a caller
/// can tell an intact stream (0 written) from a cut message. Never raises
/// SIGPIPE. Disconnected on EPIPE/ECONNRESET, errno kept for the caller.
IoStatus write_all(int fd, const char* data, size_t len, int timeout_ms, size_t& written);

/// Last error of a transport: a fixed buffer guarded by a mutex, so setting
/// it in the cyclic path neither allocates nor throws.
class ErrorText {
 public:
  /// printf-style; truncates at the buffer size.
  void set(const char* format, ...) __attribute__((format(printf, 2, 3)));
  void clear();
  std::string get() const;

 private:
  mutable std::mutex mutex_;
  std::array<char, 512> text_{};
};

}  // namespace rise::hil::io::detail
