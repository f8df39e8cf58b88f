#include "firmware_protocol/console_can.hpp"

#include <catch2/catch.hpp>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fp = rise::firmware_protocol;

namespace {

std::string hex(std::span<const uint8_t> bytes) {
  std::string out;
  char buf[4];
  for (const uint8_t b : bytes) {
    std::snprintf(buf, sizeof buf, "%s%02X", out.empty() ? "" : " ", b);
    out += buf;
  }
  return out;
}

// Field-by-field equality (the protocol structs have no operator==).
bool same(const fp::Message& a, const fp::Message& b) {
  if (a.index() != b.index()) return false;
  if (const auto* x = std::get_if<fp::AxesFrame>(&a)) {
    const auto& y = std::get<fp::AxesFrame>(b);
    return (x->group & 1) == (y.group & 1) && x->raw == y.raw;
  }
  if (const auto* x = std::get_if<fp::ButtonsFrame>(&a))
    return x->pressed == std::get<fp::ButtonsFrame>(b).pressed;
  if (const auto* x = std::get_if<fp::SwitchesFrame>(&a))
    return x->position == std::get<fp::SwitchesFrame>(b).position;
  if (const auto* x = std::get_if<fp::HeartbeatFrame>(&a)) {
    const auto& y = std::get<fp::HeartbeatFrame>(b);
    return x->protocol_version == y.protocol_version && x->status == y.status && x->uptime_ms == y.uptime_ms;
  }
  if (const auto* x = std::get_if<fp::IndicatorsFrame>(&a)) {
    const auto& y = std::get<fp::IndicatorsFrame>(b);
    return x->leds_on == y.leds_on && x->buzzer == y.buzzer;
  }
  const auto& x = std::get<fp::DisplayFrame>(a);
  const auto& y = std::get<fp::DisplayFrame>(b);
  return x.index == y.index && x.decimals == y.decimals && x.raw == y.raw;
}

// A frame with arbitrary payload bytes 1..7 and a correct CRC.
fp::WireFrame protected_frame(uint32_t can_id, std::array<uint8_t, fp::kFrameLength> data) {
  fp::WireFrame w{can_id, data};
  w.data[0] = fp::frame_crc(can_id, w.data);
  return w;
}

fp::DecodeError decode_error(fp::Decoder& d, const fp::WireFrame& w) {
  return d.decode(w.can_id, w.data).error;
}

fp::WireFrame buttons(uint8_t node, uint8_t counter, uint32_t pressed = 0x5) {
  return fp::encode(fp::ButtonsFrame{pressed}, node, counter);
}

}  // namespace

TEST_CASE("CRC-8 SAE J1850 gives the catalogue check value for \"123456789\"", "[firmware_protocol]") {
  const std::string check = "123456789";
  const std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(check.data()), check.size());
  CHECK(fp::crc8_sae_j1850(bytes) == 0x4B);
  SECTION("an empty input leaves init XOR xorout") { CHECK(fp::crc8_sae_j1850({}) == 0x00); }
  SECTION("a split computation continues from the un-XORed register") {
    const uint8_t first = fp::crc8_sae_j1850(bytes.first(4));
    CHECK(fp::crc8_sae_j1850(bytes.subspan(4), static_cast<uint8_t>(first ^ 0xFF)) == 0x4B);
  }
}

TEST_CASE("frame CRC covers both identifier bytes and payload bytes 1..7, not byte 0",
          "[firmware_protocol]") {
  std::array<uint8_t, fp::kFrameLength> data{0x00, 0x03, 0x00, 0x40, 0x00, 0xE0, 0x00, 0x00};
  const uint8_t crc = fp::frame_crc(0x111, data);
  // Reference: CRC-8 SAE J1850 of 11 01 03 00 40 00 E0 00 00.
  const std::array<uint8_t, 9> input{0x11, 0x01, 0x03, 0x00, 0x40, 0x00, 0xE0, 0x00, 0x00};
  CHECK(crc == fp::crc8_sae_j1850(input));
  data[0] = 0x5A;
  CHECK(fp::frame_crc(0x111, data) == crc);
  CHECK(fp::frame_crc(0x211, data) != crc);  // high byte of the id counts
  CHECK(fp::frame_crc(0x112, data) != crc);  // low byte of the id counts
  for (std::size_t i = 1; i < fp::kFrameLength; ++i) {
    auto changed = data;
    changed[i] ^= 0x01;
    CHECK(fp::frame_crc(0x111, changed) != crc);
  }
}

TEST_CASE("identifiers are the base id plus the node id", "[firmware_protocol]") {
  const auto [type, base, period_ms] = GENERATE(table<fp::FrameType, uint32_t, uint32_t>({
      {fp::FrameType::Axes0, 0x110, 10},
      {fp::FrameType::Axes1, 0x120, 10},
      {fp::FrameType::Buttons, 0x130, 20},
      {fp::FrameType::Switches, 0x140, 20},
      {fp::FrameType::Heartbeat, 0x170, 100},
      {fp::FrameType::Indicators, 0x210, 0},
      {fp::FrameType::Display, 0x220, 0},
  }));
  CHECK(fp::base_id(type) == base);
  CHECK(fp::can_id(type, 0) == base);
  CHECK(fp::can_id(type, 15) == base + 15);
  CHECK(fp::nominal_period_ms(type) == period_ms);
  CHECK(std::string(fp::to_string(type)) != "?");
}

TEST_CASE("axis scaling clamps to -1..1 and rounds to the nearest raw value", "[firmware_protocol]") {
  CHECK(fp::axis_from_unit(0.f) == 0);
  CHECK(fp::axis_from_unit(1.f) == 32767);
  CHECK(fp::axis_from_unit(-1.f) == -32767);
  CHECK(fp::axis_from_unit(2.5f) == 32767);
  CHECK(fp::axis_from_unit(-7.f) == -32767);
  CHECK(fp::axis_from_unit(0.5f) == 16384);    // 16383.5 rounds away from zero
  CHECK(fp::axis_from_unit(-0.25f) == -8192);  // -8191.75
  CHECK(fp::axis_from_unit(1.f / 32767.f) == 1);
  CHECK(fp::axis_to_unit(32767) == Approx(1.0).margin(1e-7));
  CHECK(fp::axis_to_unit(-32767) == Approx(-1.0).margin(1e-7));
  CHECK(fp::axis_to_unit(fp::kAxisInvalid) == Approx(-1.0).margin(1e-7));
  CHECK(fp::axis_to_unit(16384) == Approx(0.500015).margin(1e-6));
  for (int raw = -32767; raw <= 32767; raw += 97)
    CHECK(fp::axis_from_unit(fp::axis_to_unit(static_cast<int16_t>(raw))) == raw);
}

TEST_CASE("every message type survives encode and decode", "[firmware_protocol]") {
  const fp::Message message =
      GENERATE(fp::Message{fp::AxesFrame{0, {0, 0, 0}}},
               fp::Message{fp::AxesFrame{0, {32767, -32767, fp::kAxisInvalid}}},
               fp::Message{fp::AxesFrame{1, {1, -1, 12345}}}, fp::Message{fp::ButtonsFrame{0}},
               fp::Message{fp::ButtonsFrame{0xFFFFFFFFu}}, fp::Message{fp::ButtonsFrame{0x80000001u}},
               fp::Message{fp::SwitchesFrame{{0, 1, 2, 3, 254, fp::kSwitchInvalid}}},
               fp::Message{fp::HeartbeatFrame{fp::kProtocolVersion, fp::PanelStatus::Init, 0}},
               fp::Message{fp::HeartbeatFrame{fp::kProtocolVersion, fp::PanelStatus::Shutdown, 0xFFFFFFFFu}},
               fp::Message{fp::HeartbeatFrame{fp::kProtocolVersion, fp::PanelStatus::Fault, 123456}},
               fp::Message{fp::IndicatorsFrame{0xA5A5A5A5u, fp::BuzzerMode::Beep}},
               fp::Message{fp::IndicatorsFrame{0, fp::BuzzerMode::Off}},
               fp::Message{fp::DisplayFrame{3, 9, -2147483647 - 1}},
               fp::Message{fp::DisplayFrame{255, 0, 2147483647}});
  const auto node = GENERATE(uint8_t{0}, uint8_t{1}, uint8_t{15});
  const auto counter = GENERATE(uint8_t{0}, uint8_t{7}, uint8_t{15});

  const fp::WireFrame w = fp::encode(message, node, counter);
  CHECK(w.can_id == fp::can_id(fp::frame_type_of(message), node));
  CHECK(w.data[1] == counter);  // reserved high nibble is 0

  fp::Decoder decoder(node);
  const fp::DecodeResult r = decoder.decode(w.can_id, w.data);
  REQUIRE(r.ok());
  CHECK(r.type == fp::frame_type_of(message));
  CHECK(r.counter == counter);
  CHECK(same(r.message, message));
}

TEST_CASE("decoder reports every kind of error", "[firmware_protocol]") {
  fp::Decoder decoder(1);
  const fp::WireFrame good = buttons(1, 4);

  SECTION("good frame") { CHECK(decode_error(decoder, good) == fp::DecodeError::None); }
  SECTION("unknown identifier") {
    CHECK(decoder.decode(0x131 + 1, good.data).error == fp::DecodeError::UnknownId);  // node 2's buttons
    CHECK(decoder.decode(0x100, good.data).error == fp::DecodeError::UnknownId);
    CHECK(decoder.decode(0x80000131u, good.data).error == fp::DecodeError::UnknownId);
    CHECK(decode_error(decoder, buttons(0, 4)) == fp::DecodeError::UnknownId);
  }
  SECTION("bad length") {
    CHECK(decoder.decode(good.can_id, std::span(good.data).first(7)).error == fp::DecodeError::BadLength);
    CHECK(decoder.decode(good.can_id, {}).error == fp::DecodeError::BadLength);
    const std::array<uint8_t, 9> nine{};
    CHECK(decoder.decode(good.can_id, nine).error == fp::DecodeError::BadLength);
  }
  SECTION("bad CRC") {
    for (std::size_t i = 0; i < fp::kFrameLength; ++i) {
      auto data = good.data;
      data[i] ^= 0x10;
      CHECK(decoder.decode(good.can_id, data).error == fp::DecodeError::BadCrc);
    }
    // The same bytes under another frame type's id: the Data ID catches it.
    CHECK(decoder.decode(fp::can_id(fp::FrameType::Switches, 1), good.data).error == fp::DecodeError::BadCrc);
  }
  SECTION("bad values") {
    const uint32_t heartbeat_id = fp::can_id(fp::FrameType::Heartbeat, 1);
    const uint32_t indicators_id = fp::can_id(fp::FrameType::Indicators, 1);
    const uint32_t display_id = fp::can_id(fp::FrameType::Display, 1);
    CHECK(decode_error(decoder, protected_frame(heartbeat_id, {0, 0, 1, 4, 0, 0, 0, 0})) ==
          fp::DecodeError::BadValue);
    CHECK(decode_error(decoder, protected_frame(indicators_id, {0, 0, 0, 0, 0, 0, 3, 0})) ==
          fp::DecodeError::BadValue);
    CHECK(decode_error(decoder, protected_frame(display_id, {0, 0, 0, 10, 0, 0, 0, 0})) ==
          fp::DecodeError::BadValue);
    // The largest legal values pass.
    CHECK(decode_error(decoder, protected_frame(heartbeat_id, {0, 1, 1, 3, 0, 0, 0, 0})) ==
          fp::DecodeError::None);
    CHECK(decode_error(decoder, protected_frame(indicators_id, {0, 1, 0, 0, 0, 0, 2, 0})) ==
          fp::DecodeError::None);
    CHECK(decode_error(decoder, protected_frame(display_id, {0, 1, 0, 9, 0, 0, 0, 0})) ==
          fp::DecodeError::None);
  }
  SECTION("repeated counter") {
    REQUIRE(decode_error(decoder, good) == fp::DecodeError::None);
    CHECK(decode_error(decoder, good) == fp::DecodeError::RepeatedCounter);
  }
  SECTION("skipped counter") {
    REQUIRE(decode_error(decoder, good) == fp::DecodeError::None);
    const fp::DecodeResult r = decoder.decode(good.can_id, buttons(1, 6).data);
    CHECK(r.error == fp::DecodeError::SkippedCounter);
    CHECK(r.counter == 6);
  }
  for (std::size_t i = 0; i < fp::kDecodeErrorCount; ++i)
    CHECK(std::string(fp::to_string(static_cast<fp::DecodeError>(i))) != "?");
}

TEST_CASE("decoder checks id, then length, then CRC, then values, then the counter", "[firmware_protocol]") {
  fp::Decoder decoder(0);
  const uint32_t heartbeat_id = fp::can_id(fp::FrameType::Heartbeat, 0);
  auto bad_value = protected_frame(heartbeat_id, {0, 0, 1, 7, 0, 0, 0, 0});
  SECTION("unknown id wins over a bad length") {
    CHECK(decoder.decode(0x7FF, std::span(bad_value.data).first(3)).error == fp::DecodeError::UnknownId);
  }
  SECTION("bad length wins over a bad CRC") {
    auto data = bad_value.data;
    data[0] ^= 0xFF;
    CHECK(decoder.decode(heartbeat_id, std::span(data).first(7)).error == fp::DecodeError::BadLength);
  }
  SECTION("bad CRC wins over a bad value") {
    auto data = bad_value.data;
    data[0] ^= 0xFF;
    CHECK(decoder.decode(heartbeat_id, data).error == fp::DecodeError::BadCrc);
  }
  SECTION("bad value wins over a repeated counter") {
    const auto ok = protected_frame(heartbeat_id, {0, 0, 1, 1, 0, 0, 0, 0});
    REQUIRE(decode_error(decoder, ok) == fp::DecodeError::None);
    CHECK(decode_error(decoder, bad_value) == fp::DecodeError::BadValue);  // counter 0 again
  }
}

TEST_CASE("decoder accepts the alive counter wrapping from 15 to 0", "[firmware_protocol]") {
  fp::Decoder decoder(2);
  for (int i = 0; i < 40; ++i) {
    const auto counter = static_cast<uint8_t>((9 + i) % 16);
    INFO("frame " << i << " counter " << int(counter));
    CHECK(decode_error(decoder, buttons(2, counter)) == fp::DecodeError::None);
  }
}

TEST_CASE("decoder resynchronises on the counter after a counter error", "[firmware_protocol]") {
  fp::Decoder decoder(0);
  REQUIRE(decode_error(decoder, buttons(0, 0)) == fp::DecodeError::None);
  SECTION("after a skip the next in-sequence frame is accepted") {
    CHECK(decode_error(decoder, buttons(0, 5)) == fp::DecodeError::SkippedCounter);
    CHECK(decode_error(decoder, buttons(0, 6)) == fp::DecodeError::None);
  }
  SECTION("after a repeat the next in-sequence frame is accepted") {
    CHECK(decode_error(decoder, buttons(0, 0)) == fp::DecodeError::RepeatedCounter);
    CHECK(decode_error(decoder, buttons(0, 1)) == fp::DecodeError::None);
  }
  SECTION("a backwards jump counts as a skip") {
    CHECK(decode_error(decoder, buttons(0, 15)) == fp::DecodeError::SkippedCounter);  // (15 - 0) mod 16 = 15
    CHECK(decode_error(decoder, buttons(0, 0)) == fp::DecodeError::None);
  }
}

TEST_CASE("decoder leaves the counter alone when it rejects a frame for CRC, length or value",
          "[firmware_protocol]") {
  fp::Decoder decoder(0);
  REQUIRE(decode_error(decoder, buttons(0, 3)) == fp::DecodeError::None);
  auto corrupt = buttons(0, 9);
  corrupt.data[0] ^= 0x01;
  CHECK(decode_error(decoder, corrupt) == fp::DecodeError::BadCrc);
  const auto short_frame = buttons(0, 9);
  CHECK(decoder.decode(short_frame.can_id, std::span(short_frame.data).first(5)).error ==
        fp::DecodeError::BadLength);
  const uint32_t display_id = fp::can_id(fp::FrameType::Display, 0);
  REQUIRE(decode_error(decoder, protected_frame(display_id, {0, 3, 0, 0, 0, 0, 0, 0})) ==
          fp::DecodeError::None);
  CHECK(decode_error(decoder, protected_frame(display_id, {0, 9, 0, 12, 0, 0, 0, 0})) ==
        fp::DecodeError::BadValue);
  CHECK(decode_error(decoder, buttons(0, 4)) == fp::DecodeError::None);
  CHECK(decode_error(decoder, protected_frame(display_id, {0, 4, 0, 0, 0, 0, 0, 0})) ==
        fp::DecodeError::None);
}

TEST_CASE("decoder keeps one counter per frame type and honours max_counter_delta", "[firmware_protocol]") {
  SECTION("types are independent") {
    fp::Decoder decoder(0);
    CHECK(decode_error(decoder, buttons(0, 3)) == fp::DecodeError::None);
    CHECK(decode_error(decoder, fp::encode(fp::SwitchesFrame{}, 0, 3)) == fp::DecodeError::None);
    CHECK(decode_error(decoder, fp::encode(fp::AxesFrame{0, {}}, 0, 3)) == fp::DecodeError::None);
    CHECK(decode_error(decoder, fp::encode(fp::AxesFrame{1, {}}, 0, 3)) == fp::DecodeError::None);
    CHECK(decode_error(decoder, buttons(0, 4)) == fp::DecodeError::None);
  }
  SECTION("a delta up to the limit is accepted") {
    fp::Decoder decoder(0, 3);
    REQUIRE(decode_error(decoder, buttons(0, 14)) == fp::DecodeError::None);
    CHECK(decode_error(decoder, buttons(0, 1)) == fp::DecodeError::None);  // lost 15 and 0
    CHECK(decode_error(decoder, buttons(0, 5)) == fp::DecodeError::SkippedCounter);
  }
}

TEST_CASE("decoder reset forgets the counters", "[firmware_protocol]") {
  fp::Decoder decoder(0);
  REQUIRE(decode_error(decoder, buttons(0, 3)) == fp::DecodeError::None);
  REQUIRE(decode_error(decoder, buttons(0, 3)) == fp::DecodeError::RepeatedCounter);
  decoder.reset();
  CHECK(decode_error(decoder, buttons(0, 3)) == fp::DecodeError::None);
  decoder.reset();
  CHECK(decode_error(decoder, buttons(0, 11)) == fp::DecodeError::None);
  CHECK(decode_error(decoder, buttons(0, 12)) == fp::DecodeError::None);
}

TEST_CASE("decoder ignores the reserved high nibble of byte 1", "[firmware_protocol]") {
  fp::Decoder decoder(0);
  auto w = buttons(0, 3, 0x21);
  w.data[1] = 0xA3;
  w.data[0] = fp::frame_crc(w.can_id, w.data);
  const fp::DecodeResult r = decoder.decode(w.can_id, w.data);
  REQUIRE(r.ok());
  CHECK(r.counter == 3);
  CHECK(std::get<fp::ButtonsFrame>(r.message).pressed == 0x21);
}

TEST_CASE("encoder counts each frame type separately and wraps after 15", "[firmware_protocol]") {
  fp::Encoder encoder(5);
  CHECK(encoder.node_id() == 5);
  for (int i = 0; i < 20; ++i) {
    const fp::WireFrame b = encoder.next(fp::ButtonsFrame{});
    CHECK(b.can_id == 0x135);
    CHECK(b.data[1] == i % 16);
  }
  CHECK(encoder.next(fp::AxesFrame{0, {}}).data[1] == 0);
  CHECK(encoder.next(fp::AxesFrame{1, {}}).data[1] == 0);
  CHECK(encoder.next(fp::AxesFrame{0, {}}).data[1] == 1);
  fp::Decoder decoder(5);
  for (int i = 0; i < 40; ++i)
    CHECK(decode_error(decoder, encoder.next(fp::SwitchesFrame{})) == fp::DecodeError::None);
}

TEST_CASE("encode produces the worked examples of firmware_protocol/README.md", "[firmware_protocol]") {
  // Node 1, Axes0 (0.5, -0.25, 0.0), counter 3; Buttons 0, 5 and 17 held, counter 3.
  const fp::AxesFrame axes{0,
                           {fp::axis_from_unit(0.5f), fp::axis_from_unit(-0.25f), fp::axis_from_unit(0.f)}};
  const fp::WireFrame a = fp::encode(axes, 1, 3);
  CHECK(a.can_id == 0x111);
  CHECK(hex(a.data) == "B0 03 00 40 00 E0 00 00");
  const fp::WireFrame b = fp::encode(fp::ButtonsFrame{(1u << 0) | (1u << 5) | (1u << 17)}, 1, 3);
  CHECK(b.can_id == 0x131);
  CHECK(hex(b.data) == "CA 03 21 00 02 00 00 00");

  // The README shows the same bytes (so the document cannot drift from the code).
  std::ifstream in(std::string(RISE_SOURCE_DIR) + "/firmware_protocol/README.md");
  REQUIRE(in.good());
  std::stringstream readme;
  readme << in.rdbuf();
  CHECK(readme.str().find("B0 03 00 40 00 E0 00 00") != std::string::npos);
  CHECK(readme.str().find("11 01 03 00 40 00 E0 00 00") != std::string::npos);
  CHECK(readme.str().find("CA 03 21 00 02 00 00 00") != std::string::npos);
}
