#pragma once

// What the whole-chain tests share: where the sources and the built programs
// are, and whether Debian's python3-can is there for /usr/bin/python3 (a
// TCP port for an emulator to listen on: tests/process_support.hpp).

#include <filesystem>
#include <string>

#include "process/child_process.hpp"
#include "tests/process_support.hpp"

namespace rise::test {

inline const std::string kSource = RISE_SOURCE_DIR;
inline const std::string kBin = std::string(RISE_BINARY_DIR) + "/bin";

/// True when /usr/bin/python3 imports python-can (Debian's python3-can).
inline bool python_can_available() {
  if (!std::filesystem::exists("/usr/bin/python3")) return false;
  process::ChildProcess probe({"/usr/bin/python3", "-c", "import can"}, "/dev/null");
  return probe.wait_for(20000) == 0;
}

}  // namespace rise::test
