#pragma once

// What the tests that run programs share: a child's log read whole, and a
// deadline-bounded wait on a condition (a line in a log, a message seen).

#include <chrono>
#include <fstream>
#include <sstream>
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

}  // namespace rise::test
