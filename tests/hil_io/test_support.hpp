#pragma once

// Helpers for the hil/io tests: frame builders, waiting on a condition with
// a deadline, and plain TCP sockets for protocol peers written in the test.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <string_view>
#include <thread>

#include "hil/io/can_frame.hpp"

namespace rise::hil::io::test {

inline CanFrame make_frame(uint32_t id, std::initializer_list<uint8_t> bytes, bool extended = false) {
  CanFrame f;
  f.id = id;
  f.extended = extended;
  for (uint8_t b : bytes) f.data[f.len++] = b;
  return f;
}

inline CanFrame make_fd_frame(uint32_t id, uint8_t len, bool brs) {
  CanFrame f;
  f.id = id;
  f.fd = true;
  f.brs = brs;
  f.len = len;
  for (uint8_t i = 0; i < len; ++i) f.data[i] = static_cast<uint8_t>(0xA0 + i);
  return f;
}

/// Polls condition until it holds or timeout passed; true when it held.
template <class Condition>
bool wait_until(Condition condition, std::chrono::milliseconds timeout = std::chrono::seconds(5)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!condition()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

/// A TCP socket listening on 127.0.0.1 at an ephemeral port; -1 on failure.
inline int listen_loopback(uint16_t& port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t size = sizeof a;
  if (fd < 0 || ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(fd, 4) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &size) != 0) {
    if (fd >= 0) ::close(fd);
    return -1;
  }
  port = ntohs(a.sin_port);
  return fd;
}

inline int connect_loopback(uint16_t port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(port);
  if (fd < 0 || ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    if (fd >= 0) ::close(fd);
    return -1;
  }
  const int on = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &on, sizeof on);
  return fd;
}

/// Writes all of text; false on error.
inline bool write_text(int fd, std::string_view text) {
  while (!text.empty()) {
    const ssize_t n = ::send(fd, text.data(), text.size(), MSG_NOSIGNAL);
    if (n <= 0) return false;
    text.remove_prefix(static_cast<size_t>(n));
  }
  return true;
}

/// One recv() of what is there within timeout_ms; empty on timeout or close.
inline std::string read_once(int fd, int timeout_ms) {
  pollfd p{fd, POLLIN, 0};
  if (::poll(&p, 1, timeout_ms) <= 0) return {};
  char buffer[4096];
  const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
  return n > 0 ? std::string(buffer, static_cast<size_t>(n)) : std::string{};
}

/// Reads until the received text contains needle or timeout_ms passed.
inline std::string read_until(int fd, std::string_view needle, int timeout_ms) {
  std::string got;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (got.find(needle) == std::string::npos && std::chrono::steady_clock::now() < deadline) {
    got += read_once(fd, 20);
  }
  return got;
}

}  // namespace rise::hil::io::test
