#include "hil/io/posix_io.hpp"

#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstring>

#include "msgs/clock.hpp"

namespace rise::hil::io::detail {

int remaining_ms(Clock::time_point deadline) {
  const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now()).count();
  if (left <= 0) return 0;
  return left > 1'000'000'000 ? 1'000'000'000 : static_cast<int>(left);
}

const char* errno_text(int err) {
  // strerrordesc_np (glibc >= 2.32) returns a static string: no locale, no buffer.
  const char* text = strerrordesc_np(err);
  return text != nullptr ? text : "Unknown error";
}

void close_fd(int& fd) {
  if (fd >= 0) ::close(fd);
  fd = -1;
}

IoStatus wait_fd(int fd, short events, int timeout_ms) {
  const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms < 0 ? 0 : timeout_ms);
  for (;;) {
    pollfd p{fd, events, 0};
    const int n = ::poll(&p, 1, remaining_ms(deadline));
    if (n > 0) return IoStatus::Ok;
    if (n == 0) return IoStatus::Timeout;
    if (errno != EINTR) return IoStatus::Error;
  }
}

IoStatus write_all(int fd, const char* data, size_t len, int timeout_ms, size_t& written) {
  written = 0;
  const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms < 0 ? 0 : timeout_ms);
  while (written < len) {
    const ssize_t n = ::send(fd, data + written, len - written, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n > 0) {
      written += static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      const IoStatus s = wait_fd(fd, POLLOUT, remaining_ms(deadline));
      if (s != IoStatus::Ok) return s;
      continue;
    }
    if (n == 0 || errno == EPIPE || errno == ECONNRESET || errno == ENOTCONN) {
      if (n == 0) errno = EPIPE;
      return IoStatus::Disconnected;
    }
    return IoStatus::Error;
  }
  return IoStatus::Ok;
}

void ErrorText::set(const char* format, ...) {
  std::lock_guard lock(mutex_);
  va_list args;
  va_start(args, format);
  std::vsnprintf(text_.data(), text_.size(), format, args);
  va_end(args);
}

void ErrorText::clear() {
  std::lock_guard lock(mutex_);
  text_[0] = '\0';
}

std::string ErrorText::get() const {
  std::lock_guard lock(mutex_);
  return std::string(text_.data());
}

}  // namespace rise::hil::io::detail
