#pragma once

// A ModbusLink that writes every request, its answer and its timing as a
// Modbus transaction trace (modbus_trace.hpp), plus the link's reopens and
// closes, while passing everything through to the link it wraps.

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "hil/io/modbus_link.hpp"
#include "hil/io/modbus_trace.hpp"
#include "hil/io/record_file.hpp"

namespace rise::hil::io {

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
  ModbusResult read_coils(uint16_t address, std::span<uint8_t> bits) override;
  ModbusResult read_discrete_inputs(uint16_t address, std::span<uint8_t> bits) override;
  ModbusResult read_holding_registers(uint16_t address, std::span<uint16_t> registers) override;
  ModbusResult read_input_registers(uint16_t address, std::span<uint16_t> registers) override;
  ModbusResult write_coils(uint16_t address, std::span<const uint8_t> bits) override;
  ModbusResult write_registers(uint16_t address, std::span<const uint16_t> registers) override;

  bool is_open() const override { return link_->is_open(); }
  std::string last_error() const override { return link_->last_error(); }
  ModbusStatus reopen() override;
  void close() override;

  /// Lines written (the header too), and writes or flushes that failed. Thread-safe.
  int64_t lines_recorded() const { return file_.lines(); }
  int64_t write_errors() const { return file_.errors(); }

 private:
  using Clock = std::chrono::steady_clock;
  template <typename T>
  ModbusResult transact(ModbusFunction function, uint16_t address, std::span<T> values, ModbusResult result,
                        int64_t time_us, Clock::time_point start);

  std::unique_ptr<ModbusLink> link_;
  RecordFile file_;
  std::string source_;
  int unit_;
  std::string line_;
};

}  // namespace rise::hil::io
