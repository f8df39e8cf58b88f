#pragma once

// A named signal of a third-party Modbus device (panel protocol "modbus": a
// PLC, an I/O module, a panel with its own register map): one of the four
// tables of the Modbus data model (Modbus Application Protocol V1.1b3 §4.3),
// an address in it and, for a register, optionally one of its bits:
//
//   coil.N                       read with function 01, written with 15
//   discrete_input.N             read with 02
//   holding_register.N[.bit.B]   read with 03, written with 16
//   input_register.N[.bit.B]     read with 04
//
// N is the 0-based protocol address (what goes into the PDU; mbpoll -0;
// tools that count from 1 show N+1), 0..65535. B is 0..15, 0 the least
// significant bit. "input_register.5.bit.3" is bit 3 of input register 5.

#include <compare>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace rise::panels {

/// In function-code order (01 coils .. 04 input registers).
enum class ModbusTable : uint8_t { Coils, DiscreteInputs, HoldingRegisters, InputRegisters };
inline constexpr std::size_t kModbusTableCount = 4;
/// "coil", "discrete_input", "holding_register", "input_register".
const char* to_string(ModbusTable table);

struct ModbusPoint {
  ModbusTable table = ModbusTable::InputRegisters;
  uint16_t address = 0;
  int8_t bit = -1;  ///< 0..15: one bit of the register; -1: the whole register (always for coils, discrete inputs)

  /// True for the bit tables (coils, discrete inputs).
  bool bit_table() const { return table == ModbusTable::Coils || table == ModbusTable::DiscreteInputs; }
  /// True when the value is one bit: a coil, a discrete input or a register's bit.
  bool is_bit() const { return bit_table() || bit >= 0; }
  auto operator<=>(const ModbusPoint&) const = default;
};

/// How a whole register's 16 bits read as a number.
enum class ModbusValueType : uint8_t { UInt16, Int16 };

/// "holding_register.3.bit.2" → ModbusPoint; nullopt when malformed or out
/// of range (address above 65535, bit above 15, a bit of a coil). No throw,
/// no allocation.
std::optional<ModbusPoint> parse_modbus_point(std::string_view text);
/// The text parse_modbus_point() reads. Allocates: for messages.
std::string to_string(const ModbusPoint& point);

/// A register's raw 16 bits as `type` reads them (two's complement for
/// Int16). Safe in the cyclic path.
inline int32_t modbus_number(uint16_t raw, ModbusValueType type) {
  return type == ModbusValueType::Int16 ? static_cast<int32_t>(static_cast<int16_t>(raw)) : static_cast<int32_t>(raw);
}

}  // namespace rise::panels
