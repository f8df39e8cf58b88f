#pragma once

// A ModbusLink that writes every request, its answer and its timing as a
// Modbus transaction trace (modbus_trace.hpp), plus the link's reopens and
// closes, while passing everything through to the link it wraps.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <fstream>
#include <memory>
#include <string>

#include "hil/io/modbus_link.hpp"
#include "hil/io/modbus_trace.hpp"

namespace rise::io {

class RecordingModbusLink final : public ModbusLink {
 public:
  /// Records `link` into `path` (created or truncated) under the name
  /// `source`, with `unit` written on each transaction. The first line after
  /// the header says whether the link is open now. Throws std::runtime_error
  /// if the file cannot be created.
  RecordingModbusLink(std::unique_ptr<ModbusLink> link, const std::string& path, std::string source, int unit);
  ~RecordingModbusLink() override;

  /// Each passes the request on and writes its line. A failed write (disk
  /// full) is counted in write_errors(), never thrown; no allocation once
  /// the line buffer has grown to a line's length.
  ModbusResult read_discrete_inputs(uint16_t address, std::span<uint8_t> bits) override;
  ModbusResult read_input_registers(uint16_t address, std::span<uint16_t> registers) override;
  ModbusResult write_coils(uint16_t address, std::span<const uint8_t> bits) override;
  ModbusResult write_registers(uint16_t address, std::span<const uint16_t> registers) override;

  bool is_open() const override { return link_->is_open(); }
  ModbusStatus reopen() override;
  void close() override;

  /// Lines written, and writes or flushes that failed. Thread-safe.
  int64_t lines_recorded() const { return recorded_; }
  int64_t write_errors() const { return write_errors_; }

 private:
  using Clock = std::chrono::steady_clock;
  template <typename T>
  ModbusResult transact(ModbusFunction function, uint16_t address, std::span<T> values, ModbusResult result,
                        int64_t time_us, Clock::time_point start);
  void write_line();

  std::unique_ptr<ModbusLink> link_;
  std::ofstream out_;
  std::string source_;
  int unit_;
  std::string line_;
  std::atomic<int64_t> recorded_{0};  // read by other threads (status lines)
  std::atomic<int64_t> write_errors_{0};
  Clock::time_point last_flush_;
};

}  // namespace rise::io
