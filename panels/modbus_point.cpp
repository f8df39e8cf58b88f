#include "panels/modbus_point.hpp"

#include <array>
#include <charconv>

namespace rise::panels {
namespace {

constexpr std::array<ModbusTable, kModbusTableCount> kTables = {
    ModbusTable::Coils, ModbusTable::DiscreteInputs, ModbusTable::HoldingRegisters, ModbusTable::InputRegisters};

// Decimal digits only (no sign, no leading '+'), at most `max`.
std::optional<unsigned> parse_number(std::string_view text, unsigned max) {
  if (text.empty() || text.size() > 5) return std::nullopt;
  unsigned value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || value > max) return std::nullopt;
  return value;
}

}  // namespace

const char* to_string(ModbusTable table) {
  switch (table) {
    case ModbusTable::Coils: return "coil";
    case ModbusTable::DiscreteInputs: return "discrete_input";
    case ModbusTable::HoldingRegisters: return "holding_register";
    case ModbusTable::InputRegisters: return "input_register";
  }
  return "?";
}

std::optional<ModbusPoint> parse_modbus_point(std::string_view text) {
  const auto dot = text.find('.');
  if (dot == std::string_view::npos) return std::nullopt;
  const std::string_view table = text.substr(0, dot);
  std::string_view rest = text.substr(dot + 1);
  ModbusPoint point;
  bool known = false;
  for (const ModbusTable t : kTables)
    if (table == to_string(t)) {
      point.table = t;
      known = true;
    }
  if (!known) return std::nullopt;
  const auto bit_at = rest.find(".bit.");
  const auto address = parse_number(rest.substr(0, bit_at), 65535);
  if (!address) return std::nullopt;
  point.address = static_cast<uint16_t>(*address);
  if (bit_at != std::string_view::npos) {
    const auto bit = parse_number(rest.substr(bit_at + 5), 15);
    if (!bit || point.bit_table()) return std::nullopt;
    point.bit = static_cast<int8_t>(*bit);
  }
  return point;
}

std::string to_string(const ModbusPoint& point) {
  std::string text = std::string(to_string(point.table)) + "." + std::to_string(point.address);
  if (point.bit >= 0) text += ".bit." + std::to_string(point.bit);
  return text;
}

}  // namespace rise::panels
