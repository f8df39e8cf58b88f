#pragma once

// What the tests that run programs share: a child's log read whole, a
// deadline-bounded wait on a condition (a line in a log, a message seen),
// and a TCP port for an emulator to listen on.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>

namespace rise::test {

/// The whole file ("" when it cannot be read).
inline std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Checks `condition` every 5 ms until it holds (true) or timeout_ms passed (false).
template <class Condition>
bool wait_until(Condition condition, int timeout_ms) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (!condition()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

/// Waits until the file (a child's log) holds `text`.
inline bool wait_for_text(const std::string& file, const std::string& text, int timeout_ms = 10000) {
  return wait_until([&] { return read_file(file).find(text) != std::string::npos; }, timeout_ms);
}

/// A TCP port on 127.0.0.1 that nothing holds now, for a listener whose
/// port its peer must know before either starts. Below the kernel's
/// ephemeral range (32768-60999, where any client's connection may take a
/// port at any moment: a port derived from the pid there was once taken),
/// from a start that differs between test processes, each checked by a bind.
inline uint16_t free_tcp_port() {
  static uint16_t next = static_cast<uint16_t>(20000 + (::getpid() * 97) % 12000);
  for (int tries = 0; tries < 12000; ++tries) {
    const uint16_t port = next;
    next = next + 1 >= 32000 ? 20000 : static_cast<uint16_t>(next + 1);
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0) break;
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(port);
    const bool free = ::bind(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) == 0;
    ::close(fd);
    if (free) return port;
  }
  throw std::runtime_error("no free TCP port on 127.0.0.1 in 20000..31999");
}

}  // namespace rise::test
