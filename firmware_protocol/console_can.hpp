#pragma once

// The RISE console's CAN protocol, version 1 (see firmware_protocol/README.md
// for the byte layout, the worked example and console_can_v1.dbc).
// Pure encode/decode: no I/O, no allocation, no exceptions.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <variant>

namespace rise::firmware_protocol {

inline constexpr uint8_t kProtocolVersion = 1;
inline constexpr std::size_t kFrameLength = 8;     ///< every v1 frame is a classic 8-byte frame
inline constexpr std::size_t kAxesPerFrame = 3;
inline constexpr std::size_t kAxisFrames = 2;      ///< axes 0..2 and 3..5
inline constexpr std::size_t kMaxAxes = kAxesPerFrame * kAxisFrames;
inline constexpr std::size_t kMaxButtons = 32;
inline constexpr std::size_t kMaxSwitches = 6;
inline constexpr std::size_t kMaxLeds = 32;
inline constexpr int16_t kAxisInvalid = INT16_MIN; ///< "not available" (sensor fault, not yet read)
inline constexpr uint8_t kSwitchInvalid = 0xFF;    ///< "not available"

/// 11-bit identifiers: base + node id (0..15). Lower id wins arbitration, so
/// the axes that steer the robot come first.
enum class FrameType : uint8_t {
  Axes0 = 0,      ///< 0x110 + node, console → host, every 10 ms
  Axes1 = 1,      ///< 0x120 + node, console → host, every 10 ms
  Buttons = 2,    ///< 0x130 + node, console → host, every 20 ms and on change
  Switches = 3,   ///< 0x140 + node, console → host, every 20 ms and on change
  Heartbeat = 4,  ///< 0x170 + node, console → host, every 100 ms
  Indicators = 5, ///< 0x210 + node, host → console: LEDs and buzzer
  Display = 6,    ///< 0x220 + node, host → console: one display value
};
inline constexpr std::size_t kFrameTypeCount = 7;

/// Base identifier of a frame type (add the node id).
uint32_t base_id(FrameType type);
/// The CAN identifier of a frame type for a node (0..15).
uint32_t can_id(FrameType type, uint8_t node_id);
/// Nominal period of the cyclic frames in milliseconds (0 for event frames).
uint32_t nominal_period_ms(FrameType type);
const char* to_string(FrameType type);

enum class PanelStatus : uint8_t { Init = 0, Operational = 1, Fault = 2, Shutdown = 3 };
const char* to_string(PanelStatus status);

enum class BuzzerMode : uint8_t { Off = 0, On = 1, Beep = 2 };

/// Axes frame: three signed 16-bit axes, -32767..32767 ↔ -1..1, kAxisInvalid
/// for an axis the firmware cannot read.
struct AxesFrame {
  uint8_t group = 0;  ///< 0 → axes 0..2 (Axes0), 1 → axes 3..5 (Axes1)
  std::array<int16_t, kAxesPerFrame> raw{};
};
struct ButtonsFrame {
  uint32_t pressed = 0;  ///< bit i = button i held
};
struct SwitchesFrame {
  std::array<uint8_t, kMaxSwitches> position{};  ///< position index, kSwitchInvalid if unknown
};
struct HeartbeatFrame {
  uint8_t protocol_version = kProtocolVersion;
  PanelStatus status = PanelStatus::Init;
  uint32_t uptime_ms = 0;
};
struct IndicatorsFrame {
  uint32_t leds_on = 0;  ///< bit i = LED i lit
  BuzzerMode buzzer = BuzzerMode::Off;
};
struct DisplayFrame {
  uint8_t index = 0;     ///< display number on the console
  uint8_t decimals = 0;  ///< value = raw / 10^decimals
  int32_t raw = 0;
};

using Message = std::variant<AxesFrame, ButtonsFrame, SwitchesFrame, HeartbeatFrame,
                             IndicatorsFrame, DisplayFrame>;

FrameType frame_type_of(const Message& message);

/// Scales a raw axis value to -1..1 (kAxisInvalid must be checked first).
float axis_to_unit(int16_t raw);
/// Scales -1..1 (clamped) to the raw axis value, rounding to nearest.
int16_t axis_from_unit(float value);

/// CRC-8 SAE J1850: polynomial 0x1D, initial 0xFF, final XOR 0xFF
/// ("123456789" → 0x4B). Safe in the cyclic path.
uint8_t crc8_sae_j1850(std::span<const uint8_t> bytes, uint8_t crc = 0xFF);

/// The frame's end-to-end CRC: CRC-8 SAE J1850 over the identifier (low byte,
/// then high byte, as AUTOSAR E2E profile 1 "Data ID" both bytes) followed by
/// payload bytes 1..7 (byte 0 holds the CRC).
uint8_t frame_crc(uint32_t can_id, std::span<const uint8_t, kFrameLength> payload);

/// One frame on the wire: identifier and 8 data bytes.
struct WireFrame {
  uint32_t can_id = 0;
  std::array<uint8_t, kFrameLength> data{};
};

/// Writes one message as a protected frame with the given alive counter
/// (0..15). Safe in the cyclic path.
WireFrame encode(const Message& message, uint8_t node_id, uint8_t counter);

enum class DecodeError : uint8_t {
  None = 0,
  UnknownId,        ///< not a v1 identifier of this node
  BadLength,        ///< DLC is not 8
  BadCrc,           ///< byte 0 does not match frame_crc()
  RepeatedCounter,  ///< same alive counter as the previous frame of this type
  SkippedCounter,   ///< alive counter jumped by more than max_counter_delta
  BadValue,         ///< field out of range (panel status, buzzer mode, display decimals)
};
inline constexpr std::size_t kDecodeErrorCount = 7;
const char* to_string(DecodeError error);

struct DecodeResult {
  DecodeError error = DecodeError::None;
  FrameType type = FrameType::Axes0;  ///< valid unless error == UnknownId
  uint8_t counter = 0;
  Message message{};
  bool ok() const { return error == DecodeError::None; }
};

/// Stateful decoder of one node's frames: checks length, CRC and the alive
/// counter per frame type. The first frame of a type after construction or
/// reset() is accepted whatever its counter (AUTOSAR E2E "initial" state).
/// A frame with a repeated or skipped counter is rejected, and the next frame
/// is checked against it (resynchronisation). No allocation, no throw.
class Decoder {
 public:
  explicit Decoder(uint8_t node_id, uint8_t max_counter_delta = 1);

  DecodeResult decode(uint32_t can_id, std::span<const uint8_t> data);
  /// Forgets the counters (e.g. after the source was stale or re-opened).
  void reset();
  uint8_t node_id() const { return node_id_; }

 private:
  uint8_t node_id_;
  uint8_t max_counter_delta_;
  std::array<int8_t, kFrameTypeCount> last_counter_{};  // -1 = none yet
};

/// Keeps one alive counter per frame type for a sender.
class Encoder {
 public:
  explicit Encoder(uint8_t node_id) : node_id_(node_id) {}
  /// Encodes with this type's next counter. Safe in the cyclic path.
  WireFrame next(const Message& message);
  uint8_t node_id() const { return node_id_; }

 private:
  uint8_t node_id_;
  std::array<uint8_t, kFrameTypeCount> counter_{};
};

}  // namespace rise::firmware_protocol
