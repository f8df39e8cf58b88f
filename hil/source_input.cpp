#include "hil/source_input.hpp"

#include <algorithm>
#include <array>

#include "firmware_protocol/console_modbus.hpp"
#include "hil/io/can_error.hpp"

namespace rise::hil {
namespace fp = rise::firmware_protocol;

bool apply_can_frame(PanelMapper& mapper, std::size_t source, const io::CanFrame& frame, int64_t now_us) {
  if (frame.error) return mapper.on_bus_error(source, io::describe_can_error(frame), now_us);
  const bool is_dbc = mapper.definition().sources[source].is_dbc();
  // rise-can-v1 is classic 11-bit only; a DBC device may use FD and 29-bit ids.
  if (frame.remote || (!is_dbc && frame.fd)) return false;
  return mapper.on_frame(source, frame.id, std::span<const uint8_t>(frame.data.data(), frame.len), now_us,
                         frame.extended);
}

bool apply_modbus_result(PanelMapper& mapper, std::size_t source, const io::ModbusResult& result, bool link_open,
                         int64_t now_us) {
  using E = PanelMapper::SourceError;
  switch (result.status) {
    case io::ModbusStatus::Ok: return true;
    case io::ModbusStatus::Timeout: mapper.on_source_error(source, E::Timeout, now_us); break;
    case io::ModbusStatus::Exception: mapper.on_source_error(source, E::Exception, now_us); break;
    case io::ModbusStatus::CrcError: mapper.on_source_error(source, E::LinkCrc, now_us); break;
    case io::ModbusStatus::Disconnected:
    case io::ModbusStatus::Error: break;
  }
  if (link_open) return true;
  if (result.status != io::ModbusStatus::Timeout) mapper.on_connection(source, false, now_us);
  return false;
}

bool apply_modbus_inputs(PanelMapper& mapper, std::size_t source, std::span<const uint16_t> registers,
                         std::span<const uint8_t> bits, std::optional<uint16_t>& last_counter, int64_t now_us) {
  using E = PanelMapper::SourceError;
  std::array<uint16_t, fp::modbus_ir::kCount> block{};
  std::copy_n(registers.begin(), std::min(registers.size(), block.size()), block.begin());
  uint32_t discrete = 0;
  for (std::size_t i = 0; i < bits.size() && i < 32; ++i)
    if (bits[i] != 0) discrete |= 1u << i;
  const fp::ModbusInputsResult d = fp::decode_inputs(block, discrete, last_counter);
  switch (d.error) {
    case fp::ModbusDecodeError::None:
      last_counter = d.inputs.alive_counter;
      return mapper.on_inputs(source, d.inputs, now_us);
    case fp::ModbusDecodeError::BadCrc: mapper.on_source_error(source, E::BadCrc, now_us); break;
    case fp::ModbusDecodeError::BadValue: mapper.on_source_error(source, E::BadValue, now_us); break;
    case fp::ModbusDecodeError::StaleCounter: mapper.on_source_error(source, E::StaleCounter, now_us); break;
  }
  return false;
}

bool apply_modbus_poll(PanelMapper& mapper, std::size_t source, const ModbusPoll& poll,
                       std::optional<uint16_t>& last_counter, int64_t now_us) {
  if (mapper.definition().sources[source].is_generic_modbus()) return mapper.on_modbus_poll(source, poll, now_us);
  return apply_modbus_inputs(mapper, source, poll.registers(0), poll.bits(1), last_counter, now_us);
}

}  // namespace rise::hil
