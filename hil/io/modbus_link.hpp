#pragma once

// A Modbus master's link to one slave (the console), behind one small
// interface; libmodbus backs TCP and RTU. Chosen by URL (hil/io/modbus_url.hpp).
//
// Threading: a ModbusLink (and its libmodbus context) is used from one
// thread only — libmodbus contexts are not thread-safe; open one link per
// thread.

#include <cstdint>
#include <memory>
#include <span>
#include <string_view>

#include "hil/io/modbus_url.hpp"

namespace rise::hil::io {

enum class ModbusStatus : uint8_t {
  Ok = 0,
  Timeout,       ///< no (complete) answer within timeout_ms
  Exception,     ///< the slave answered with an exception (code kept)
  CrcError,      ///< RTU frame with a bad CRC (libmodbus EMBBADCRC)
  Disconnected,  ///< not open, or the connection broke: reopen()
  Error,         ///< anything else (bad answer, bad arguments)
};
const char* to_string(ModbusStatus status);

struct ModbusResult {
  ModbusStatus status = ModbusStatus::Ok;
  uint8_t exception_code = 0;  ///< Modbus exception code when status == Exception
  bool ok() const { return status == ModbusStatus::Ok; }
};

struct ModbusCounters {
  int64_t requests = 0;
  int64_t ok = 0;
  int64_t timeouts = 0;
  int64_t exceptions = 0;
  int64_t crc_errors = 0;
  int64_t disconnects = 0;
  int64_t errors = 0;
  int64_t reopens = 0;  ///< successful reopen() calls
};

class ModbusLink {
 public:
  virtual ~ModbusLink() = default;

  /// Reads bits.size() coils (function 01) starting at `address`; bits[i]
  /// is 0 or 1. Blocks at most timeout_ms. No throw.
  virtual ModbusResult read_coils(uint16_t address, std::span<uint8_t> bits) = 0;
  /// Reads bits.size() discrete inputs (function 02) starting at `address`;
  /// bits[i] is 0 or 1. Blocks at most timeout_ms. No throw.
  virtual ModbusResult read_discrete_inputs(uint16_t address, std::span<uint8_t> bits) = 0;
  /// Reads holding registers (function 03). Blocks at most timeout_ms. No throw.
  virtual ModbusResult read_holding_registers(uint16_t address, std::span<uint16_t> registers) = 0;
  /// Reads input registers (function 04). Blocks at most timeout_ms. No throw.
  virtual ModbusResult read_input_registers(uint16_t address, std::span<uint16_t> registers) = 0;
  /// Writes coils (function 15). No throw.
  virtual ModbusResult write_coils(uint16_t address, std::span<const uint8_t> bits) = 0;
  /// Writes holding registers (function 16). No throw.
  virtual ModbusResult write_registers(uint16_t address, std::span<const uint16_t> registers) = 0;

  virtual bool is_open() const = 0;
  /// Closes and connects again, once; the caller does the back-off.
  virtual ModbusStatus reopen() = 0;
  virtual void close() = 0;
  /// Why the link is down, after a failed reopen() or a request that closed
  /// it: the OS's or libmodbus's error with the URL ("" when it never failed).
  virtual std::string last_error() const { return {}; }

  const ModbusCounters& counters() const { return counters_; }

 protected:
  ModbusResult count(ModbusResult r);
  ModbusCounters counters_;
};

/// Opens a client link for modbus+tcp:// or modbus+rtu://, or a replay of a
/// recorded trace for replay://FILE.modbus.log (hil/io/replay_modbus_link.hpp).
/// Throws std::invalid_argument for a bad URL (std::runtime_error for a
/// trace that cannot be read); a peer that is not there yet leaves the link
/// closed (is_open() false) for the caller to reopen().
std::unique_ptr<ModbusLink> open_modbus_link(std::string_view url);
std::unique_ptr<ModbusLink> open_modbus_link(const ModbusAddress& address);

}  // namespace rise::hil::io
