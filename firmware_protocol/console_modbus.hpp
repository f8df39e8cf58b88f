#pragma once

// The RISE console's Modbus register map, version 1 (protocol rise-modbus-v1;
// see "Modbus register map v1" in firmware_protocol/README.md). The same
// logical console as rise-can-v1: axis.0-5, button.0-31 and switch.0-5 mean
// the same on both protocols. Pure encode/decode: no I/O, no allocation, no
// exceptions.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "firmware_protocol/console_can.hpp"

namespace rise::firmware_protocol {

// Addresses are 0-based protocol addresses (mbpoll -0; 1-based tools add 1).
inline constexpr uint16_t kModbusDiscreteInputs = 32;  ///< DI i = button i
inline constexpr uint16_t kModbusCoils = 32;           ///< coil i = LED i
inline constexpr uint16_t kModbusDisplays = 8;         ///< display indices 0..7

/// Input registers (function 04).
namespace modbus_ir {
inline constexpr uint16_t kAxis0 = 0;       ///< 0..5: axes, int16 two's complement
inline constexpr uint16_t kSwitch0 = 6;     ///< 6..11: switch positions 0..254, 255 = n/a
inline constexpr uint16_t kStatus = 12;     ///< PanelStatus 0..3
inline constexpr uint16_t kVersion = 13;    ///< protocol version, 1
inline constexpr uint16_t kUptimeHigh = 14; ///< uptime ms, high word first
inline constexpr uint16_t kUptimeLow = 15;
inline constexpr uint16_t kAlive = 16;      ///< +1 every firmware cycle (10 ms), wraps 65535 → 0
inline constexpr uint16_t kCrc = 17;        ///< CRC-16/MODBUS over registers 0..16, big-endian bytes
inline constexpr uint16_t kCount = 18;
}  // namespace modbus_ir

/// Holding registers (functions 03/16): 0 buzzer, then per display k (0..7)
/// 1+3k decimals, 2+3k raw high word, 3+3k raw low word.
namespace modbus_hr {
inline constexpr uint16_t kBuzzer = 0;
inline constexpr uint16_t kDisplay0 = 1;
inline constexpr uint16_t kPerDisplay = 3;
inline constexpr uint16_t kCount = 1 + kPerDisplay * kModbusDisplays;  ///< 25
}  // namespace modbus_hr

/// The console's inputs as one consistent block (what a CAN cycle spreads
/// over the Axes, Buttons, Switches and Heartbeat frames).
struct ConsoleInputs {
  std::array<int16_t, kMaxAxes> axes{};                ///< kAxisInvalid = not available
  uint32_t buttons = 0;                                ///< bit i = button i held
  std::array<uint8_t, kMaxSwitches> switches{};        ///< kSwitchInvalid = not available
  PanelStatus status = PanelStatus::Init;
  uint8_t protocol_version = kProtocolVersion;
  uint32_t uptime_ms = 0;
  uint16_t alive_counter = 0;
  bool operator==(const ConsoleInputs&) const = default;
};

/// Registers and discrete inputs as the console's firmware serves them.
struct ModbusInputBlock {
  std::array<uint16_t, modbus_ir::kCount> registers{};
  uint32_t discrete_bits = 0;  ///< bit i = discrete input i
};

/// LEDs and displays as the host writes them.
struct ModbusFeedbackBlock {
  uint32_t coil_bits = 0;  ///< bit i = coil i
  std::array<uint16_t, modbus_hr::kCount> holding{};
};

/// CRC-16/MODBUS: reflected polynomial 0xA001 (0x8005), initial 0xFFFF, no
/// final XOR ("123456789" → 0x4B37). Safe in the cyclic path.
uint16_t crc16_modbus(std::span<const uint8_t> bytes, uint16_t crc = 0xFFFF);

/// The map's end-to-end CRC: crc16_modbus over registers 0..16, each register
/// high byte first. Safe in the cyclic path.
uint16_t input_block_crc(std::span<const uint16_t, modbus_ir::kCount> registers);

/// The firmware side: fills every register including the CRC. Switch values
/// and the version are written as they are (0..255). Safe in the cyclic path.
ModbusInputBlock encode_inputs(const ConsoleInputs& inputs);

enum class ModbusDecodeError : uint8_t {
  None = 0,
  BadCrc,        ///< register 17 does not match input_block_crc()
  BadValue,      ///< a switch, status or version register outside its range
  StaleCounter,  ///< alive counter equal to the previous block's: no new data
};
inline constexpr std::size_t kModbusDecodeErrorCount = 4;
const char* to_string(ModbusDecodeError error);

struct ModbusInputsResult {
  ModbusDecodeError error = ModbusDecodeError::None;
  ConsoleInputs inputs{};  ///< filled unless error is BadCrc or BadValue
  bool ok() const { return error == ModbusDecodeError::None; }
};

/// Checks and decodes one polled block, in this order: CRC (BadCrc), ranges
/// (BadValue), then the alive counter against `last_counter` (the previous
/// accepted block's; nullopt for the first block after a (re)connect) →
/// StaleCounter when it has not moved. A poll faster than the firmware cycle
/// sees StaleCounter now and then; it is "no new data", not a fault: the host
/// fails the source only when no fresh block came for its timeout_ms.
/// Safe in the cyclic path.
ModbusInputsResult decode_inputs(std::span<const uint16_t, modbus_ir::kCount> registers,
                                 uint32_t discrete_bits,
                                 std::optional<uint16_t> last_counter = std::nullopt);

/// The host side: LEDs → coils, buzzer and displays → holding registers.
/// Displays with an index ≥ kModbusDisplays are not in the map and are
/// skipped. Safe in the cyclic path.
ModbusFeedbackBlock encode_feedback(const IndicatorsFrame& indicators,
                                    std::span<const DisplayFrame> displays);

struct ModbusFeedbackResult {
  ModbusDecodeError error = ModbusDecodeError::None;  ///< None or BadValue
  IndicatorsFrame indicators{};
  std::array<DisplayFrame, kModbusDisplays> displays{};  ///< displays[k].index == k
  bool ok() const { return error == ModbusDecodeError::None; }
};

/// The console side: BadValue for a buzzer mode above 2 or decimals above 9.
/// Safe in the cyclic path.
ModbusFeedbackResult decode_feedback(const ModbusFeedbackBlock& block);

}  // namespace rise::firmware_protocol
