#pragma once

// One poll of a Modbus source: the reads it makes, what they read, and the
// writes of its feedback.
//
// rise-modbus-v1: input registers 0..17 (the block under the map's CRC),
// then discrete inputs 0..31. modbus (a third-party device): for each of
// the four tables a control reads, one read from its lowest to its highest
// bound address, in function-code order (01 coils, 02 discrete inputs, 03
// holding registers, 04 input registers): the fewest requests that read
// every bound point (the definition loader checked that each span fits one
// request).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "hil/io/modbus_link.hpp"
#include "hil/io/modbus_trace.hpp"
#include "panels/panel_definition.hpp"

namespace rise::hil {

struct ModbusRead {
  io::ModbusFunction function = io::ModbusFunction::ReadInputRegisters;
  uint16_t address = 0;
  uint16_t count = 0;
};

/// The reads of one poll of `source` (a Modbus source of `definition`), in
/// the order they go out. Allocates: call once per source.
std::vector<ModbusRead> modbus_poll_reads(const panels::PanelDefinition& definition, std::size_t source);

/// The values of one poll: read from a link by read(), or set from a
/// recorded trace by store().
class ModbusPoll {
 public:
  explicit ModbusPoll(std::vector<ModbusRead> reads);

  const std::vector<ModbusRead>& reads() const { return reads_; }
  /// Performs the reads in order, stopping at the first that fails; its
  /// result, or Ok when every read was answered. No throw; allocates nothing.
  io::ModbusResult read(io::ModbusLink& link);
  /// Index of the read of this request, or nullopt.
  std::optional<std::size_t> find(io::ModbusFunction function, uint16_t address, uint16_t count) const;
  /// Sets read `i`'s values as a trace records them (registers, or bits as
  /// 0/1); the first count() of them. No throw.
  void store(std::size_t i, std::span<const uint16_t> values);

  /// Read `i`'s registers (empty for a bit read) or bits (empty for a register read).
  std::span<const uint16_t> registers(std::size_t i) const { return registers_[i]; }
  std::span<const uint8_t> bits(std::size_t i) const { return bits_[i]; }
  /// The value of `point` in what was read: 0/1 for a coil, a discrete
  /// input or a register's bit, the register's 16 bits otherwise; nullopt
  /// when no read covers it. No throw; allocates nothing.
  std::optional<uint16_t> value(const panels::ModbusPoint& point) const;

 private:
  std::vector<ModbusRead> reads_;
  std::vector<std::vector<uint16_t>> registers_;  // per read
  std::vector<std::vector<uint8_t>> bits_;        // per read
};

/// One value of a modbus source's feedback: an LED's coil or holding
/// register (1 lit, 0 dark) or a display's holding register.
struct ModbusWrite {
  panels::ModbusPoint point;
  uint16_t value = 0;
};

/// Writes a modbus source's feedback when it changes, each point in a
/// request of its own (function 15 for a coil, 16 for a register, count 1),
/// so that the device's other coils and registers are never touched.
class ModbusFeedbackWriter {
 public:
  /// Writes each of `writes` whose value differs from the one last written
  /// at its place (all of them after forget()); stops at the first failure,
  /// which is tried again at the next call. Its result, or Ok. No throw;
  /// allocates only when `writes` grows.
  io::ModbusResult write(io::ModbusLink& link, std::span<const ModbusWrite> writes);
  /// The link was lost (the device may have restarted): write all next time.
  void forget() { last_.clear(); }

 private:
  std::vector<std::optional<uint16_t>> last_;
};

}  // namespace rise::hil
