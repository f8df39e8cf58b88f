#include "firmware_protocol/console_modbus.hpp"

namespace rise::firmware_protocol {
namespace {

constexpr uint8_t kMaxDecimals = 9;

// CRC-16/MODBUS table (Modbus over Serial Line V1.02, §6.2.2: reflected 0xA001).
constexpr std::array<uint16_t, 256> make_crc16_table() {
  std::array<uint16_t, 256> table{};
  for (unsigned i = 0; i < 256; ++i) {
    unsigned crc = i;
    for (int bit = 0; bit < 8; ++bit) crc = (crc & 1u) != 0 ? ((crc >> 1) ^ 0xA001u) : (crc >> 1);
    table[i] = static_cast<uint16_t>(crc);
  }
  return table;
}
constexpr std::array<uint16_t, 256> kCrc16Table = make_crc16_table();

uint16_t high_word(uint32_t v) { return static_cast<uint16_t>(v >> 16); }
uint16_t low_word(uint32_t v) { return static_cast<uint16_t>(v & 0xFFFFu); }
uint32_t join_words(uint16_t high, uint16_t low) { return (static_cast<uint32_t>(high) << 16) | low; }

}  // namespace

uint16_t crc16_modbus(std::span<const uint8_t> bytes, uint16_t crc) {
  for (const uint8_t b : bytes)
    crc = static_cast<uint16_t>((crc >> 8) ^ kCrc16Table[static_cast<uint8_t>((crc ^ b) & 0xFFu)]);
  return crc;
}

uint16_t input_block_crc(std::span<const uint16_t, modbus_ir::kCount> registers) {
  std::array<uint8_t, 2 * modbus_ir::kCrc> bytes{};
  for (std::size_t i = 0; i < modbus_ir::kCrc; ++i) {
    bytes[2 * i] = static_cast<uint8_t>(registers[i] >> 8);
    bytes[2 * i + 1] = static_cast<uint8_t>(registers[i] & 0xFFu);
  }
  return crc16_modbus(bytes);
}

const char* to_string(ModbusDecodeError error) {
  switch (error) {
    case ModbusDecodeError::None: return "None";
    case ModbusDecodeError::BadCrc: return "BadCrc";
    case ModbusDecodeError::BadValue: return "BadValue";
    case ModbusDecodeError::StaleCounter: return "StaleCounter";
  }
  return "?";
}

ModbusInputBlock encode_inputs(const ConsoleInputs& in) {
  ModbusInputBlock block;
  auto& r = block.registers;
  for (std::size_t i = 0; i < kMaxAxes; ++i) r[modbus_ir::kAxis0 + i] = static_cast<uint16_t>(in.axes[i]);
  for (std::size_t i = 0; i < kMaxSwitches; ++i) r[modbus_ir::kSwitch0 + i] = in.switches[i];
  r[modbus_ir::kStatus] = static_cast<uint16_t>(in.status);
  r[modbus_ir::kVersion] = in.protocol_version;
  r[modbus_ir::kUptimeHigh] = high_word(in.uptime_ms);
  r[modbus_ir::kUptimeLow] = low_word(in.uptime_ms);
  r[modbus_ir::kAlive] = in.alive_counter;
  r[modbus_ir::kCrc] = input_block_crc(r);
  block.discrete_bits = in.buttons;
  return block;
}

ModbusInputsResult decode_inputs(std::span<const uint16_t, modbus_ir::kCount> r, uint32_t discrete_bits,
                                 std::optional<uint16_t> last_counter) {
  ModbusInputsResult result;
  if (r[modbus_ir::kCrc] != input_block_crc(r)) {
    result.error = ModbusDecodeError::BadCrc;
    return result;
  }
  for (std::size_t i = 0; i < kMaxSwitches; ++i)
    if (r[modbus_ir::kSwitch0 + i] > 0xFF) result.error = ModbusDecodeError::BadValue;
  if (r[modbus_ir::kStatus] > static_cast<uint16_t>(PanelStatus::Shutdown) || r[modbus_ir::kVersion] > 0xFF)
    result.error = ModbusDecodeError::BadValue;
  if (result.error != ModbusDecodeError::None) return result;

  ConsoleInputs& in = result.inputs;
  for (std::size_t i = 0; i < kMaxAxes; ++i) in.axes[i] = static_cast<int16_t>(r[modbus_ir::kAxis0 + i]);
  for (std::size_t i = 0; i < kMaxSwitches; ++i) in.switches[i] = static_cast<uint8_t>(r[modbus_ir::kSwitch0 + i]);
  in.status = static_cast<PanelStatus>(r[modbus_ir::kStatus]);
  in.protocol_version = static_cast<uint8_t>(r[modbus_ir::kVersion]);
  in.uptime_ms = join_words(r[modbus_ir::kUptimeHigh], r[modbus_ir::kUptimeLow]);
  in.alive_counter = r[modbus_ir::kAlive];
  in.buttons = discrete_bits;
  if (last_counter && *last_counter == in.alive_counter) result.error = ModbusDecodeError::StaleCounter;
  return result;
}

ModbusFeedbackBlock encode_feedback(const IndicatorsFrame& indicators, std::span<const DisplayFrame> displays) {
  ModbusFeedbackBlock block;
  block.coil_bits = indicators.leds_on;
  block.holding[modbus_hr::kBuzzer] = static_cast<uint16_t>(indicators.buzzer);
  for (const DisplayFrame& d : displays) {
    if (d.index >= kModbusDisplays) continue;
    const std::size_t at = modbus_hr::kDisplay0 + modbus_hr::kPerDisplay * d.index;
    const auto raw = static_cast<uint32_t>(d.raw);
    block.holding[at] = d.decimals;
    block.holding[at + 1] = high_word(raw);
    block.holding[at + 2] = low_word(raw);
  }
  return block;
}

ModbusFeedbackResult decode_feedback(const ModbusFeedbackBlock& block) {
  ModbusFeedbackResult result;
  const uint16_t buzzer = block.holding[modbus_hr::kBuzzer];
  if (buzzer > static_cast<uint16_t>(BuzzerMode::Beep)) result.error = ModbusDecodeError::BadValue;
  result.indicators.leds_on = block.coil_bits;
  result.indicators.buzzer = result.ok() ? static_cast<BuzzerMode>(buzzer) : BuzzerMode::Off;
  for (uint8_t k = 0; k < kModbusDisplays; ++k) {
    const std::size_t at = modbus_hr::kDisplay0 + modbus_hr::kPerDisplay * k;
    DisplayFrame& d = result.displays[k];
    d.index = k;
    if (block.holding[at] > kMaxDecimals) {
      result.error = ModbusDecodeError::BadValue;
      continue;
    }
    d.decimals = static_cast<uint8_t>(block.holding[at]);
    d.raw = static_cast<int32_t>(join_words(block.holding[at + 1], block.holding[at + 2]));
  }
  return result;
}

}  // namespace rise::firmware_protocol
