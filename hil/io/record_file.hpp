#pragma once

// The file a recorder writes its lines into (RecordingBus, RecordingModbusLink):
// buffered, flushed at least every 100 ms so that a killed daemon loses at
// most that much, and a write that fails (a full disk) is counted, never
// thrown: the traffic it records goes on.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <fstream>
#include <string>
#include <string_view>

namespace rise::hil::io {

class RecordFile {
 public:
  /// Creates or truncates `path`. Throws std::runtime_error
  /// "PATH: cannot create the WHAT" when it cannot.
  RecordFile(const std::string& path, std::string_view what);
  ~RecordFile();
  RecordFile(const RecordFile&) = delete;
  RecordFile& operator=(const RecordFile&) = delete;

  /// Writes `line` and a newline; false when the write or its flush failed
  /// (counted in errors()). From one thread at a time. No allocation, no throw.
  bool write_line(std::string_view line);

  /// Lines written, and writes or flushes that failed. Thread-safe.
  int64_t lines() const { return lines_; }
  int64_t errors() const { return errors_; }

 private:
  std::ofstream out_;
  std::chrono::steady_clock::time_point last_flush_;
  std::atomic<int64_t> lines_{0};
  std::atomic<int64_t> errors_{0};
};

}  // namespace rise::hil::io
