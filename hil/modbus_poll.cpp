#include "hil/modbus_poll.hpp"

#include <algorithm>
#include <array>

#include "firmware_protocol/console_modbus.hpp"

namespace rise::hil {
namespace {

namespace fp = rise::firmware_protocol;
using io::ModbusFunction;
using panels::ModbusTable;

// Tables in function-code order: 01, 02, 03, 04.
constexpr std::array<ModbusFunction, panels::kModbusTableCount> kReadFunction = {
    ModbusFunction::ReadCoils, ModbusFunction::ReadDiscreteInputs, ModbusFunction::ReadHoldingRegisters,
    ModbusFunction::ReadInputRegisters};

ModbusFunction read_function(ModbusTable table) { return kReadFunction[static_cast<std::size_t>(table)]; }

}  // namespace

std::vector<ModbusRead> modbus_poll_reads(const panels::PanelDefinition& definition, std::size_t source) {
  if (!definition.sources[source].is_generic_modbus())
    return {{ModbusFunction::ReadInputRegisters, 0, fp::modbus_ir::kCount},
            {ModbusFunction::ReadDiscreteInputs, 0, fp::kModbusDiscreteInputs}};
  std::array<std::optional<std::pair<uint16_t, uint16_t>>, panels::kModbusTableCount> spans;
  for (const auto& c : definition.controls) {
    if (c.source != source || !c.modbus_point) continue;
    auto& span = spans[static_cast<std::size_t>(c.modbus_point->table)];
    const uint16_t a = c.modbus_point->address;
    span = span ? std::pair(std::min(span->first, a), std::max(span->second, a)) : std::pair(a, a);
  }
  std::vector<ModbusRead> reads;
  for (std::size_t t = 0; t < spans.size(); ++t)
    if (spans[t])
      reads.push_back({kReadFunction[t], spans[t]->first, static_cast<uint16_t>(spans[t]->second - spans[t]->first + 1)});
  return reads;
}

ModbusPoll::ModbusPoll(std::vector<ModbusRead> reads)
    : reads_(std::move(reads)), registers_(reads_.size()), bits_(reads_.size()) {
  for (std::size_t i = 0; i < reads_.size(); ++i)
    (io::is_bit_function(reads_[i].function) ? bits_[i].resize(reads_[i].count)
                                             : registers_[i].resize(reads_[i].count));
}

io::ModbusResult ModbusPoll::read(io::ModbusLink& link) {
  for (std::size_t i = 0; i < reads_.size(); ++i) {
    const ModbusRead& r = reads_[i];
    io::ModbusResult result;
    switch (r.function) {
      case ModbusFunction::ReadCoils: result = link.read_coils(r.address, bits_[i]); break;
      case ModbusFunction::ReadDiscreteInputs: result = link.read_discrete_inputs(r.address, bits_[i]); break;
      case ModbusFunction::ReadHoldingRegisters: result = link.read_holding_registers(r.address, registers_[i]); break;
      case ModbusFunction::ReadInputRegisters: result = link.read_input_registers(r.address, registers_[i]); break;
      case ModbusFunction::WriteMultipleCoils:
      case ModbusFunction::WriteMultipleRegisters: result = {io::ModbusStatus::Error, 0}; break;
    }
    if (!result.ok()) return result;
  }
  return {};
}

std::optional<std::size_t> ModbusPoll::find(ModbusFunction function, uint16_t address, uint16_t count) const {
  for (std::size_t i = 0; i < reads_.size(); ++i)
    if (reads_[i].function == function && reads_[i].address == address && reads_[i].count == count) return i;
  return std::nullopt;
}

void ModbusPoll::store(std::size_t i, std::span<const uint16_t> values) {
  if (i >= reads_.size()) return;
  if (!bits_[i].empty())
    for (std::size_t k = 0; k < bits_[i].size() && k < values.size(); ++k) bits_[i][k] = values[k] != 0 ? 1 : 0;
  std::copy_n(values.begin(), std::min(values.size(), registers_[i].size()), registers_[i].begin());
}

std::optional<uint16_t> ModbusPoll::value(const panels::ModbusPoint& point) const {
  const ModbusFunction function = read_function(point.table);
  for (std::size_t i = 0; i < reads_.size(); ++i) {
    const ModbusRead& r = reads_[i];
    if (r.function != function || point.address < r.address || point.address - r.address >= r.count) continue;
    const std::size_t k = point.address - r.address;
    if (point.bit_table()) return bits_[i][k];
    const uint16_t raw = registers_[i][k];
    return point.bit >= 0 ? static_cast<uint16_t>((raw >> point.bit) & 1u) : raw;
  }
  return std::nullopt;
}

io::ModbusResult ModbusFeedbackWriter::write(io::ModbusLink& link, std::span<const ModbusWrite> writes) {
  if (last_.size() != writes.size()) last_.resize(writes.size());
  for (std::size_t i = 0; i < writes.size(); ++i) {
    const ModbusWrite& w = writes[i];
    if (last_[i] == w.value) continue;
    io::ModbusResult r;
    if (w.point.table == ModbusTable::Coils) {
      const std::array<uint8_t, 1> bit{static_cast<uint8_t>(w.value != 0 ? 1 : 0)};
      r = link.write_coils(w.point.address, bit);
    } else {
      r = link.write_registers(w.point.address, std::span<const uint16_t>(&w.value, 1));
    }
    if (!r.ok()) return r;
    last_[i] = w.value;
  }
  return {};
}

}  // namespace rise::hil
