#include "firmware_protocol/console_can.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <type_traits>

namespace rise::firmware_protocol {
namespace {

// Byte 1 of every frame: alive counter in the low nibble, high nibble reserved.
constexpr uint8_t kCounterMask = 0x0F;
constexpr uint8_t kCounterModulo = 16;
constexpr uint32_t kNodeMask = 0x0F;
constexpr uint8_t kMaxDecimals = 9;

// CRC-8 SAE J1850 table for polynomial 0x1D (MSB first, no reflection), as in
// AUTOSAR SWS CRC Library "Crc_CalculateCRC8".
constexpr std::array<uint8_t, 256> make_crc_table() {
  std::array<uint8_t, 256> table{};
  for (unsigned i = 0; i < 256; ++i) {
    unsigned crc = i;
    for (int bit = 0; bit < 8; ++bit) crc = (crc & 0x80u) != 0 ? ((crc << 1) ^ 0x1Du) : (crc << 1);
    table[i] = static_cast<uint8_t>(crc & 0xFFu);
  }
  return table;
}
constexpr std::array<uint8_t, 256> kCrcTable = make_crc_table();

constexpr std::array<uint32_t, kFrameTypeCount> kBaseIds = {0x110, 0x120, 0x130, 0x140, 0x170, 0x210, 0x220};

void put_u16(std::array<uint8_t, kFrameLength>& d, std::size_t at, uint16_t v) {
  d[at] = static_cast<uint8_t>(v & 0xFFu);
  d[at + 1] = static_cast<uint8_t>(v >> 8);
}
void put_u32(std::array<uint8_t, kFrameLength>& d, std::size_t at, uint32_t v) {
  for (std::size_t i = 0; i < 4; ++i) d[at + i] = static_cast<uint8_t>((v >> (8 * i)) & 0xFFu);
}
uint16_t get_u16(std::span<const uint8_t> d, std::size_t at) {
  return static_cast<uint16_t>(d[at] | (d[at + 1] << 8));
}
uint32_t get_u32(std::span<const uint8_t> d, std::size_t at) {
  uint32_t v = 0;
  for (std::size_t i = 0; i < 4; ++i) v |= static_cast<uint32_t>(d[at + i]) << (8 * i);
  return v;
}

// Writes the payload bytes 2..7 of a message (bytes 0 and 1 are E2E).
struct PayloadWriter {
  std::array<uint8_t, kFrameLength>& d;
  void operator()(const AxesFrame& m) const {
    for (std::size_t i = 0; i < kAxesPerFrame; ++i) put_u16(d, 2 + 2 * i, static_cast<uint16_t>(m.raw[i]));
  }
  void operator()(const ButtonsFrame& m) const { put_u32(d, 2, m.pressed); }
  void operator()(const SwitchesFrame& m) const {
    std::copy(m.position.begin(), m.position.end(), d.begin() + 2);
  }
  void operator()(const HeartbeatFrame& m) const {
    d[2] = m.protocol_version;
    d[3] = static_cast<uint8_t>(m.status);
    put_u32(d, 4, m.uptime_ms);
  }
  void operator()(const IndicatorsFrame& m) const {
    put_u32(d, 2, m.leds_on);
    d[6] = static_cast<uint8_t>(m.buzzer);
  }
  void operator()(const DisplayFrame& m) const {
    d[2] = m.index;
    d[3] = m.decimals;
    put_u32(d, 4, static_cast<uint32_t>(m.raw));
  }
};

// Reads bytes 2..7 of a frame whose type, length and CRC are already checked.
// Returns false for a field outside its range (→ BadValue).
bool read_payload(FrameType type, std::span<const uint8_t> d, Message& out) {
  switch (type) {
    case FrameType::Axes0:
    case FrameType::Axes1: {
      AxesFrame m;
      m.group = type == FrameType::Axes0 ? 0 : 1;
      for (std::size_t i = 0; i < kAxesPerFrame; ++i) m.raw[i] = static_cast<int16_t>(get_u16(d, 2 + 2 * i));
      out = m;
      return true;
    }
    case FrameType::Buttons:
      out = ButtonsFrame{get_u32(d, 2)};
      return true;
    case FrameType::Switches: {
      SwitchesFrame m;
      std::copy(d.begin() + 2, d.begin() + 2 + kMaxSwitches, m.position.begin());
      out = m;
      return true;
    }
    case FrameType::Heartbeat: {
      if (d[3] > static_cast<uint8_t>(PanelStatus::Shutdown)) return false;
      out = HeartbeatFrame{d[2], static_cast<PanelStatus>(d[3]), get_u32(d, 4)};
      return true;
    }
    case FrameType::Indicators: {
      if (d[6] > static_cast<uint8_t>(BuzzerMode::Beep)) return false;
      out = IndicatorsFrame{get_u32(d, 2), static_cast<BuzzerMode>(d[6])};
      return true;
    }
    case FrameType::Display: {
      if (d[3] > kMaxDecimals) return false;
      out = DisplayFrame{d[2], d[3], static_cast<int32_t>(get_u32(d, 4))};
      return true;
    }
  }
  return false;
}

}  // namespace

uint32_t base_id(FrameType type) { return kBaseIds[static_cast<std::size_t>(type)]; }

uint32_t can_id(FrameType type, uint8_t node_id) { return base_id(type) + (node_id & kNodeMask); }

uint32_t nominal_period_ms(FrameType type) {
  switch (type) {
    case FrameType::Axes0:
    case FrameType::Axes1:
      return 10;
    case FrameType::Buttons:
    case FrameType::Switches:
      return 20;
    case FrameType::Heartbeat:
      return 100;
    case FrameType::Indicators:
    case FrameType::Display:
      return 0;
  }
  return 0;
}

const char* to_string(FrameType type) {
  switch (type) {
    case FrameType::Axes0:
      return "Axes0";
    case FrameType::Axes1:
      return "Axes1";
    case FrameType::Buttons:
      return "Buttons";
    case FrameType::Switches:
      return "Switches";
    case FrameType::Heartbeat:
      return "Heartbeat";
    case FrameType::Indicators:
      return "Indicators";
    case FrameType::Display:
      return "Display";
  }
  return "?";
}

const char* to_string(PanelStatus status) {
  switch (status) {
    case PanelStatus::Init:
      return "Init";
    case PanelStatus::Operational:
      return "Operational";
    case PanelStatus::Fault:
      return "Fault";
    case PanelStatus::Shutdown:
      return "Shutdown";
  }
  return "?";
}

const char* to_string(DecodeError error) {
  switch (error) {
    case DecodeError::None:
      return "None";
    case DecodeError::UnknownId:
      return "UnknownId";
    case DecodeError::BadLength:
      return "BadLength";
    case DecodeError::BadCrc:
      return "BadCrc";
    case DecodeError::RepeatedCounter:
      return "RepeatedCounter";
    case DecodeError::SkippedCounter:
      return "SkippedCounter";
    case DecodeError::BadValue:
      return "BadValue";
  }
  return "?";
}

FrameType frame_type_of(const Message& message) {
  return std::visit(
      [](const auto& m) {
        using T = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<T, AxesFrame>)
          return (m.group & 1u) == 0 ? FrameType::Axes0 : FrameType::Axes1;
        else if constexpr (std::is_same_v<T, ButtonsFrame>)
          return FrameType::Buttons;
        else if constexpr (std::is_same_v<T, SwitchesFrame>)
          return FrameType::Switches;
        else if constexpr (std::is_same_v<T, HeartbeatFrame>)
          return FrameType::Heartbeat;
        else if constexpr (std::is_same_v<T, IndicatorsFrame>)
          return FrameType::Indicators;
        else
          return FrameType::Display;
      },
      message);
}

float axis_to_unit(int16_t raw) {
  // -32768 has no mirror image; it is clamped so the scale stays symmetric.
  return static_cast<float>(std::max<int16_t>(raw, -32767)) / 32767.f;
}

int16_t axis_from_unit(float value) {
  if (std::isnan(value)) return 0;
  const float clamped = std::clamp(value, -1.f, 1.f);
  return static_cast<int16_t>(std::lround(clamped * 32767.f));
}

uint8_t crc8_sae_j1850(std::span<const uint8_t> bytes, uint8_t crc) {
  // `crc` is the running register (start 0xFF); the final XOR is applied here,
  // so a split computation passes the un-XORed register: crc8(b, crc8(a) ^ 0xFF).
  for (const uint8_t b : bytes) crc = kCrcTable[static_cast<uint8_t>(crc ^ b)];
  return static_cast<uint8_t>(crc ^ 0xFFu);
}

uint8_t frame_crc(uint32_t can_id, std::span<const uint8_t, kFrameLength> payload) {
  // AUTOSAR E2E profile 1 with "Data ID both bytes": the id's low then high byte
  // enter the CRC but are not sent, so a frame under another id fails the check.
  std::array<uint8_t, 2 + kFrameLength - 1> input{};
  input[0] = static_cast<uint8_t>(can_id & 0xFFu);
  input[1] = static_cast<uint8_t>((can_id >> 8) & 0xFFu);
  std::copy(payload.begin() + 1, payload.end(), input.begin() + 2);
  return crc8_sae_j1850(input);
}

WireFrame encode(const Message& message, uint8_t node_id, uint8_t counter) {
  WireFrame frame;
  frame.can_id = can_id(frame_type_of(message), node_id);
  frame.data[1] = static_cast<uint8_t>(counter & kCounterMask);
  std::visit(PayloadWriter{frame.data}, message);
  frame.data[0] = frame_crc(frame.can_id, frame.data);
  return frame;
}

Decoder::Decoder(uint8_t node_id, uint8_t max_counter_delta)
    : node_id_(static_cast<uint8_t>(node_id & kNodeMask)), max_counter_delta_(max_counter_delta) {
  reset();
}

void Decoder::reset() { last_counter_.fill(-1); }

DecodeResult Decoder::decode(uint32_t id, std::span<const uint8_t> data) {
  DecodeResult result;
  std::size_t index = kFrameTypeCount;
  for (std::size_t i = 0; i < kFrameTypeCount; ++i)
    if (kBaseIds[i] + node_id_ == id) index = i;
  if (index == kFrameTypeCount) {
    result.error = DecodeError::UnknownId;
    return result;
  }
  result.type = static_cast<FrameType>(index);
  if (data.size() != kFrameLength) {
    result.error = DecodeError::BadLength;
    return result;
  }
  const std::span<const uint8_t, kFrameLength> frame(data.data(), kFrameLength);
  if (frame[0] != frame_crc(id, frame)) {
    result.error = DecodeError::BadCrc;
    return result;
  }
  result.counter = static_cast<uint8_t>(frame[1] & kCounterMask);
  if (!read_payload(result.type, frame, result.message)) {
    result.error = DecodeError::BadValue;
    return result;
  }
  // Alive counter check as in AUTOSAR E2E profile 1 (E2E_P01Check): repeated →
  // no new data, a jump above MaxDeltaCounter → frames were lost. The received
  // counter is stored either way so the next in-sequence frame passes.
  int8_t& last = last_counter_[index];
  const int8_t received = static_cast<int8_t>(result.counter);
  if (last >= 0) {
    const auto delta = static_cast<uint8_t>((result.counter + kCounterModulo - last) % kCounterModulo);
    if (delta == 0)
      result.error = DecodeError::RepeatedCounter;
    else if (delta > max_counter_delta_)
      result.error = DecodeError::SkippedCounter;
  }
  last = received;
  return result;
}

WireFrame Encoder::next(const Message& message) {
  uint8_t& counter = counter_[static_cast<std::size_t>(frame_type_of(message))];
  const WireFrame frame = encode(message, node_id_, counter);
  counter = static_cast<uint8_t>((counter + 1) % kCounterModulo);
  return frame;
}

}  // namespace rise::firmware_protocol
