#pragma once

// What the whole-chain tests share: where the sources and the built programs
// are, whether Debian's python3-can is there for /usr/bin/python3, and a
// TCP port for an emulator to listen on.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "process/child_process.hpp"

namespace rise::test {

inline const std::string kSource = RISE_SOURCE_DIR;
inline const std::string kBin = std::string(RISE_BINARY_DIR) + "/bin";

/// True when /usr/bin/python3 imports python-can (Debian's python3-can).
inline bool python_can_available() {
  if (!std::filesystem::exists("/usr/bin/python3")) return false;
  process::ChildProcess probe({"/usr/bin/python3", "-c", "import can"}, "/dev/null");
  return probe.wait_for(20000) == 0;
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
