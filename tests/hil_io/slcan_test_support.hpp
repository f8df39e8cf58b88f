#pragma once

// Helpers for the slcan tests: a real pty pair made by Debian's socat
// (tests/socat_ptys.hpp), and a fake Lawicel adapter ("the firmware") on the
// other end of it. The fake parses and formats slcan text itself,
// independently of hil/io/slcan_bus.

#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "hil/io/can_frame.hpp"
#include "tests/hil_io/test_support.hpp"
#include "tests/socat_ptys.hpp"

namespace rise::hil::io::test {

using rise::test::have_socat;
using rise::test::SocatPtys;

/// A fresh directory under /tmp, removed with its content.
class TempDir {
 public:
  TempDir() {
    char name[] = "/tmp/rise-slcan-XXXXXX";
    if (::mkdtemp(name) != nullptr) path_ = name;
  }
  ~TempDir() {
    std::error_code ignored;
    if (!path_.empty()) std::filesystem::remove_all(path_, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

/// How the fake adapter behaves.
struct FakeAdapterOptions {
  bool ack_transmit = false;  ///< answer t/T with `z\r`/`Z\r` as CANUSB does (else `\r`)
  char refuse = 0;            ///< first letter of a command answered with BELL
  /// Called from the adapter's thread for each frame line the bus sent (no '\r').
  std::function<void(const std::string&)> on_frame_line;
};

/// The adapter's firmware: opens its end of the pty pair and answers the
/// Lawicel commands in its own thread until the pty hangs up.
class FakeAdapter {
 public:
  explicit FakeAdapter(const std::string& path, FakeAdapterOptions options = {})
      : options_(std::move(options)) {
    fd_ = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (fd_ >= 0) thread_ = std::thread([this] { run(); });
  }
  ~FakeAdapter() {
    running_ = false;
    if (thread_.joinable()) thread_.join();
    if (fd_ >= 0) ::close(fd_);
  }
  FakeAdapter(const FakeAdapter&) = delete;
  FakeAdapter& operator=(const FakeAdapter&) = delete;

  bool opened() const { return fd_ >= 0; }
  /// Writes raw text to the bus under test; false when the pty is gone.
  bool write(std::string_view text) {
    std::lock_guard lock(write_mutex_);
    while (!text.empty()) {
      const ssize_t n = ::write(fd_, text.data(), text.size());
      if (n <= 0) return false;
      text.remove_prefix(static_cast<size_t>(n));
    }
    return true;
  }
  /// Commands received, in order, without '\r' ("C", "S6", "O").
  std::vector<std::string> commands() {
    std::lock_guard lock(mutex_);
    return commands_;
  }
  /// Frame lines received (t, T, r, R), without '\r'.
  std::vector<std::string> frame_lines() {
    std::lock_guard lock(mutex_);
    return frames_;
  }
  /// True between `O`/`L` and `C`.
  bool channel_open() const { return channel_open_.load(); }
  bool hung_up() const { return hung_up_.load(); }

 private:
  void run() {
    std::string line;
    char buffer[256];
    while (running_) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 10) <= 0) continue;
      const ssize_t n = ::read(fd_, buffer, sizeof buffer);
      if (n <= 0) {
        if (n < 0 && errno == EINTR) continue;
        hung_up_ = true;  // socat went away: the pty reads EOF or EIO
        return;
      }
      for (ssize_t i = 0; i < n; ++i) {
        if (buffer[i] != '\r') {
          line += buffer[i];
          continue;
        }
        answer(line);
        line.clear();
      }
    }
  }

  void answer(const std::string& line) {
    const char kind = line.empty() ? '\0' : line[0];
    if (kind != '\0' && kind == options_.refuse) {
      write("\a");
      return;
    }
    if (kind == 't' || kind == 'T' || kind == 'r' || kind == 'R') {
      {
        std::lock_guard lock(mutex_);
        frames_.push_back(line);
      }
      if (options_.on_frame_line) options_.on_frame_line(line);
      const bool ack = options_.ack_transmit && (kind == 't' || kind == 'T');
      write(ack ? (kind == 't' ? "z\r" : "Z\r") : "\r");
      return;
    }
    {
      std::lock_guard lock(mutex_);
      commands_.push_back(line);
    }
    if (kind == 'O' || kind == 'L') channel_open_ = true;
    if (kind == 'C') channel_open_ = false;
    const bool known = kind == 'C' || kind == 'S' || kind == 'Z' || kind == 'O' || kind == 'L';
    write(known ? "\r" : "\a");
  }

  FakeAdapterOptions options_;
  int fd_ = -1;
  std::mutex mutex_;
  std::mutex write_mutex_;
  std::vector<std::string> commands_;
  std::vector<std::string> frames_;
  std::atomic<bool> channel_open_{false};
  std::atomic<bool> hung_up_{false};
  std::atomic<bool> running_{true};
  std::thread thread_;
};

/// The test's own slcan formatting: "t1233112233" for id 0x123, 11 22 33.
inline std::string slcan_text(const CanFrame& f) {
  char text[40];
  int n = std::snprintf(text, sizeof text, f.extended ? "%c%08X%u" : "%c%03X%u",
                        f.remote ? (f.extended ? 'R' : 'r') : (f.extended ? 'T' : 't'),
                        static_cast<unsigned>(f.id), static_cast<unsigned>(f.len));
  for (unsigned i = 0; !f.remote && i < f.len; ++i) {
    n += std::snprintf(text + n, sizeof text - static_cast<size_t>(n), "%02X",
                       static_cast<unsigned>(f.data[i]));
  }
  return std::string(text, static_cast<size_t>(n));
}

/// The test's own slcan parsing of one line without '\r'; nullopt if malformed.
inline std::optional<CanFrame> parse_slcan_text(const std::string& line) {
  if (line.empty()) return std::nullopt;
  CanFrame f;
  f.extended = line[0] == 'T' || line[0] == 'R';
  f.remote = line[0] == 'r' || line[0] == 'R';
  if (!f.extended && !f.remote && line[0] != 't') return std::nullopt;
  const size_t digits = f.extended ? 8 : 3;
  if (line.size() < digits + 2) return std::nullopt;
  f.id = static_cast<uint32_t>(std::stoul(line.substr(1, digits), nullptr, 16));
  f.len = static_cast<uint8_t>(line[digits + 1] - '0');
  if (f.len > 8) return std::nullopt;
  if (!f.remote && line.size() < digits + 2 + 2u * f.len) return std::nullopt;
  for (size_t i = 0; !f.remote && i < f.len; ++i) {
    f.data[i] = static_cast<uint8_t>(std::stoul(line.substr(digits + 2 + 2 * i, 2), nullptr, 16));
  }
  return f;
}

}  // namespace rise::hil::io::test
