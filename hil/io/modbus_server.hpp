#pragma once

// A Modbus slave serving one register map from its own thread (the console
// emulator's side): modbus+tcp-listen://HOST:PORT?unit=N (several clients at
// once) or modbus+rtu-listen:///dev/pts/N?baud=...&unit=N.

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <string_view>
#include <thread>

#include "hil/io/modbus_url.hpp"

struct _modbus;
struct _modbus_mapping_t;

namespace rise::hil::io {

/// Sizes of the four tables, each starting at address 0.
struct ModbusTableSizes {
  uint16_t coils = 32;
  uint16_t discrete_inputs = 32;
  uint16_t holding_registers = 25;
  uint16_t input_registers = 18;
};

class ModbusServer {
 public:
  /// Binds / opens the port and starts serving. Throws std::runtime_error
  /// (or std::invalid_argument for a bad URL) when it cannot; its message is
  /// "HOST:PORT: address in use" when another server listens there.
  ModbusServer(std::string_view url, ModbusTableSizes sizes);
  ~ModbusServer();
  ModbusServer(const ModbusServer&) = delete;
  ModbusServer& operator=(const ModbusServer&) = delete;

  /// Thread-safe: replaces input registers and discrete inputs at once, so a
  /// client never reads a half-updated block. Bit i of `bits` = DI i.
  void set_inputs(std::span<const uint16_t> input_registers, uint32_t discrete_bits);
  /// Thread-safe: coils (bit i = coil i, first 32) and holding registers.
  uint32_t coil_bits() const;
  void holding_registers(std::span<uint16_t> out) const;
  /// Thread-safe: one table's values from `address` on, as a device's own
  /// logic sets them (a third-party device's points; bits are 0/1). What
  /// lies outside the table is left out.
  void set_coils(uint16_t address, std::span<const uint8_t> bits);
  void set_discrete_inputs(uint16_t address, std::span<const uint8_t> bits);
  void set_holding_registers(uint16_t address, std::span<const uint16_t> registers);
  void set_input_registers(uint16_t address, std::span<const uint16_t> registers);
  /// Thread-safe: coils from `address` on, 0/1.
  void coils(uint16_t address, std::span<uint8_t> out) const;
  /// Requests answered that wrote coils or registers (functions 05, 06, 15, 16).
  int64_t writes_served() const { return writes_.load(); }
  int64_t requests_served() const { return requests_.load(); }
  /// TCP: the bound port (useful with port 0). RTU: 0.
  uint16_t port() const { return port_; }

 private:
  void serve_tcp();
  void serve_rtu();
  void reply(const uint8_t* query, int length);
  // Copies `from` into table[address..] of a table of `size`: what fits.
  template <typename T>
  void put(T* table, int size, uint16_t address, std::span<const T> from);

  ModbusAddress address_;
  _modbus* ctx_ = nullptr;
  _modbus_mapping_t* mapping_ = nullptr;
  mutable std::mutex mutex_;  // guards mapping_
  int listen_fd_ = -1;
  uint16_t port_ = 0;
  std::atomic<bool> running_{true};
  std::atomic<int64_t> writes_{0};
  std::atomic<int64_t> requests_{0};
  std::thread thread_;
};

}  // namespace rise::hil::io
