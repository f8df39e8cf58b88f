// console_can_v1.dbc must describe exactly what the C++ codec puts on the wire.
#include <catch2/catch.hpp>
#include <map>
#include <string>
#include <vector>

#include "firmware_protocol/console_can.hpp"
#include "firmware_protocol/dbc.hpp"

namespace fp = rise::firmware_protocol;

namespace {

const fp::DbcDatabase& console_dbc() {
  static const fp::DbcDatabase db =
      fp::DbcDatabase::load(std::string(RISE_SOURCE_DIR) + "/firmware_protocol/console_can_v1.dbc");
  return db;
}

struct Decoded {
  std::map<std::string, double> value;
  std::map<std::string, int64_t> raw;
  std::map<std::string, std::string> label;
};

Decoded decode_with_dbc(const fp::DbcMessage& m, std::span<const uint8_t> data) {
  Decoded out;
  for (const auto& d : console_dbc().decode(m, data)) {
    out.value[d.signal->name] = d.value;
    out.raw[d.signal->name] = d.raw;
    out.label[d.signal->name] = std::string(d.label());
  }
  return out;
}

// The physical values the DBC should hold for a message, from the C++ side.
std::vector<std::pair<std::string, double>> expected_signals(const fp::Message& message) {
  std::vector<std::pair<std::string, double>> v;
  std::visit(
      [&](const auto& m) {
        using T = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<T, fp::AxesFrame>) {
          for (std::size_t i = 0; i < fp::kAxesPerFrame; ++i)
            v.emplace_back("Axis" + std::to_string((m.group & 1) * fp::kAxesPerFrame + i),
                           m.raw[i] / 32767.0);
        } else if constexpr (std::is_same_v<T, fp::ButtonsFrame>) {
          for (std::size_t i = 0; i < fp::kMaxButtons; ++i)
            v.emplace_back("Button" + std::to_string(i), (m.pressed >> i) & 1u);
        } else if constexpr (std::is_same_v<T, fp::SwitchesFrame>) {
          for (std::size_t i = 0; i < fp::kMaxSwitches; ++i)
            v.emplace_back("Switch" + std::to_string(i), m.position[i]);
        } else if constexpr (std::is_same_v<T, fp::HeartbeatFrame>) {
          v.emplace_back("ProtocolVersion", m.protocol_version);
          v.emplace_back("PanelStatus", static_cast<double>(m.status));
          v.emplace_back("UptimeMs", m.uptime_ms);
        } else if constexpr (std::is_same_v<T, fp::IndicatorsFrame>) {
          for (std::size_t i = 0; i < fp::kMaxLeds; ++i)
            v.emplace_back("Led" + std::to_string(i), (m.leds_on >> i) & 1u);
          v.emplace_back("Buzzer", static_cast<double>(m.buzzer));
        } else {
          v.emplace_back("DisplayIndex", m.index);
          v.emplace_back("DisplayDecimals", m.decimals);
          v.emplace_back("DisplayRaw", m.raw);
        }
      },
      message);
  return v;
}

}  // namespace

TEST_CASE("console DBC lists every v1 frame of node 0 with its id, length and period",
          "[firmware_protocol]") {
  const auto& db = console_dbc();
  CHECK(db.messages().size() == fp::kFrameTypeCount);
  for (std::size_t i = 0; i < fp::kFrameTypeCount; ++i) {
    const auto type = static_cast<fp::FrameType>(i);
    const fp::DbcMessage* m = db.find(fp::can_id(type, 0), false);
    INFO(fp::to_string(type));
    REQUIRE(m != nullptr);
    CHECK(m->name == fp::to_string(type));
    CHECK(m->dlc == fp::kFrameLength);
    CHECK(m->cycle_time_ms == fp::nominal_period_ms(type));
    CHECK(m->signals.at(0).name == m->name + "_Crc");
    CHECK(m->signals.at(1).name == m->name + "_AliveCounter");
  }
}

TEST_CASE("console DBC decodes encoded frames to the values the C++ decoder gives", "[firmware_protocol]") {
  const fp::Message message = GENERATE(
      fp::Message{fp::AxesFrame{0, {16384, -8192, 0}}},
      fp::Message{fp::AxesFrame{1, {32767, -32767, fp::kAxisInvalid}}},
      fp::Message{fp::ButtonsFrame{0x80020021u}}, fp::Message{fp::ButtonsFrame{0xFFFFFFFFu}},
      fp::Message{fp::SwitchesFrame{{0, 1, 2, 7, 200, fp::kSwitchInvalid}}},
      fp::Message{fp::HeartbeatFrame{fp::kProtocolVersion, fp::PanelStatus::Operational, 3'000'000'123u}},
      fp::Message{fp::HeartbeatFrame{fp::kProtocolVersion, fp::PanelStatus::Shutdown, 0}},
      fp::Message{fp::IndicatorsFrame{0x0000F00Fu, fp::BuzzerMode::Beep}},
      fp::Message{fp::IndicatorsFrame{0xFFFFFFFFu, fp::BuzzerMode::Off}},
      fp::Message{fp::DisplayFrame{2, 3, -123456}}, fp::Message{fp::DisplayFrame{255, 9, 2147483647}});
  const auto counter = GENERATE(uint8_t{0}, uint8_t{9}, uint8_t{15});

  const fp::WireFrame w = fp::encode(message, 0, counter);
  fp::Decoder decoder(0);
  const fp::DecodeResult cpp = decoder.decode(w.can_id, w.data);
  REQUIRE(cpp.ok());

  const fp::DbcMessage* m = console_dbc().find(w.can_id, false);
  REQUIRE(m != nullptr);
  const Decoded dbc = decode_with_dbc(*m, w.data);
  CHECK(dbc.raw.at(m->name + "_Crc") == w.data[0]);
  CHECK(dbc.raw.at(m->name + "_AliveCounter") == cpp.counter);

  // What the C++ decoder returned, seen through the DBC's signals.
  for (const auto& [name, value] : expected_signals(cpp.message)) {
    INFO(m->name << "." << name);
    REQUIRE(dbc.value.count(name) == 1);
    CHECK(dbc.value.at(name) == Approx(value).margin(1e-9));
  }
  CHECK(dbc.value.size() == expected_signals(cpp.message).size() + 2);

  // Value tables and the C++ helpers agree.
  if (const auto* a = std::get_if<fp::AxesFrame>(&cpp.message)) {
    for (std::size_t i = 0; i < fp::kAxesPerFrame; ++i) {
      const std::string name = "Axis" + std::to_string((a->group & 1) * fp::kAxesPerFrame + i);
      CHECK(dbc.raw.at(name) == a->raw[i]);
      if (a->raw[i] == fp::kAxisInvalid)
        CHECK(dbc.label.at(name) == "NotAvailable");
      else
        CHECK(dbc.value.at(name) == Approx(fp::axis_to_unit(a->raw[i])).margin(1e-6));
    }
  }
  if (const auto* s = std::get_if<fp::SwitchesFrame>(&cpp.message))
    for (std::size_t i = 0; i < fp::kMaxSwitches; ++i)
      CHECK((dbc.label.at("Switch" + std::to_string(i)) == "NotAvailable") ==
            (s->position[i] == fp::kSwitchInvalid));
  if (const auto* h = std::get_if<fp::HeartbeatFrame>(&cpp.message))
    CHECK(dbc.label.at("PanelStatus") == fp::to_string(h->status));
  if (const auto* ind = std::get_if<fp::IndicatorsFrame>(&cpp.message))
    CHECK(dbc.label.at("Buzzer") == (ind->buzzer == fp::BuzzerMode::Beep ? "Beep"
                                     : ind->buzzer == fp::BuzzerMode::On ? "On"
                                                                         : "Off"));
  if (const auto* d = std::get_if<fp::DisplayFrame>(&cpp.message)) CHECK(dbc.raw.at("DisplayRaw") == d->raw);

  SECTION("DBC encode of the same values gives the same 8 bytes") {
    std::vector<std::pair<std::string, double>> named = expected_signals(cpp.message);
    named.emplace_back(m->name + "_Crc", w.data[0]);
    named.emplace_back(m->name + "_AliveCounter", counter);
    std::vector<fp::SignalValue> values;
    for (const auto& [name, value] : named) values.push_back({name, value});
    const std::vector<uint8_t> bytes = console_dbc().encode(*m, values);
    CHECK(bytes == std::vector<uint8_t>(w.data.begin(), w.data.end()));
  }
}
