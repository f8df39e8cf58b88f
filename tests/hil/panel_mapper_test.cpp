#include <catch2/catch.hpp>

#include <cmath>

#include "hil/feedback.hpp"
#include "hil/panel_mapper.hpp"
#include "hil/panel_state_message.hpp"
#include "msgs/failsafe.hpp"
#include "panels/panel_definition.hpp"

namespace fp = rise::firmware_protocol;
using rise::hil::PanelMapper;
using rise::hil::PanelSnapshot;

namespace {

rise::panels::PanelDefinition console() {
  return rise::panels::load_panel_definition(std::string(RISE_SOURCE_DIR) +
                                             "/panels/definitions/rise_console.yaml");
}

// Plays the console's firmware into a mapper with explicit times (µs).
struct Firmware {
  PanelMapper& mapper;
  fp::Encoder encoder{0};
  std::array<int16_t, 6> axes{};
  uint32_t buttons = 0;
  std::array<uint8_t, 6> switches{0, 2, 0, 0, 0, 0};  // mode=drive, speed=fast
  fp::PanelStatus status = fp::PanelStatus::Operational;

  void feed(const fp::Message& m, int64_t t) {
    const auto w = encoder.next(m);
    mapper.on_frame(0, w.can_id, w.data, t);
  }
  // One firmware cycle: heartbeat, both axis frames, buttons, switches.
  void cycle(int64_t t) {
    feed(fp::HeartbeatFrame{fp::kProtocolVersion, status, static_cast<uint32_t>(t / 1000)}, t);
    feed(fp::AxesFrame{0, {axes[0], axes[1], axes[2]}}, t);
    feed(fp::AxesFrame{1, {axes[3], axes[4], axes[5]}}, t);
    feed(fp::ButtonsFrame{buttons}, t);
    fp::SwitchesFrame s;
    s.position = switches;
    feed(s, t);
  }
};

float axis(const PanelMapper& m, const PanelSnapshot& s, const char* name) {
  return s.controls[*m.definition().find_control(name)].axis;
}
bool pressed(const PanelMapper& m, const PanelSnapshot& s, const char* name) {
  return s.controls[*m.definition().find_control(name)].pressed;
}
uint8_t position(const PanelMapper& m, const PanelSnapshot& s, const char* name) {
  return s.controls[*m.definition().find_control(name)].position;
}
constexpr int64_t kT0 = 1'000'000;
}  // namespace

TEST_CASE("before the console's state is read every control is at its safe value and the panel is failsafe",
          "[hil]") {
  PanelMapper mapper(console());
  mapper.on_connection(0, true, kT0);
  const auto s = mapper.evaluate(kT0);
  CHECK(s.failsafe);
  CHECK(rise::msgs::has(s.failsafe_causes, rise::msgs::FailsafeCause::SourceStale));
  CHECK(pressed(mapper, s, "estop"));  // its safe value is "pressed"
  CHECK_FALSE(pressed(mapper, s, "deadman"));
  CHECK(position(mapper, s, "speed") == 0);
  CHECK(s.sources[0].stale);
}

TEST_CASE("a healthy console's frames become named controls with deadband and scaling", "[hil]") {
  PanelMapper mapper(console());
  mapper.on_connection(0, true, kT0);
  Firmware fw{mapper};
  fw.buttons = 1u << 0;                        // dead-man held
  fw.axes[1] = fp::axis_from_unit(0.5f);       // drive_y
  fw.axes[0] = fp::axis_from_unit(0.03f);      // drive_x inside its 0.05 deadband
  fw.axes[4] = fp::axis_from_unit(-1.0f);      // arm_twist
  fw.cycle(kT0);
  const auto s = mapper.evaluate(kT0 + 1000);
  INFO(s.failsafe_reason);
  REQUIRE_FALSE(s.failsafe);
  CHECK(s.deadman);
  CHECK(axis(mapper, s, "drive_x") == 0.0f);
  // Deadband 0.05 rescaled: (0.5 - 0.05) / 0.95.
  CHECK(axis(mapper, s, "drive_y") == Approx(0.45 / 0.95).margin(1e-4));
  CHECK(axis(mapper, s, "arm_twist") == Approx(-1.0).margin(1e-6));
  CHECK(position(mapper, s, "speed") == 2);
  CHECK_FALSE(pressed(mapper, s, "estop"));
  CHECK(s.sources[0].frames_ok == 5);
}

TEST_CASE("a source without a valid frame for its timeout goes failsafe at the next evaluation",
          "[hil]") {
  PanelMapper mapper(console());
  mapper.on_connection(0, true, kT0);
  Firmware fw{mapper};
  fw.buttons = 1;
  fw.axes[1] = fp::axis_from_unit(1.0f);
  fw.cycle(kT0);
  const int64_t timeout_us = 1000 * mapper.definition().sources[0].timeout_ms;
  CHECK_FALSE(mapper.evaluate(kT0 + timeout_us).failsafe);
  const auto s = mapper.evaluate(kT0 + timeout_us + 1);
  CHECK(s.failsafe);
  CHECK(rise::msgs::has(s.failsafe_causes, rise::msgs::FailsafeCause::SourceStale));
  CHECK_FALSE(rise::msgs::has(s.failsafe_causes, rise::msgs::FailsafeCause::Estop));  // its safe value, not a press
  CHECK(s.sources[0].stale);
  CHECK(axis(mapper, s, "drive_y") == 0.0f);
  CHECK_FALSE(s.deadman);
  SECTION("and recovers when frames return") {
    fw.cycle(kT0 + timeout_us + 5000);
    CHECK_FALSE(mapper.evaluate(kT0 + timeout_us + 6000).failsafe);
  }
}

TEST_CASE("a failed protection check is counted, forces failsafe and clears after recovery_frames good frames",
          "[hil]") {
  PanelMapper mapper(console());
  mapper.on_connection(0, true, kT0);
  Firmware fw{mapper};
  fw.buttons = 1;
  fw.cycle(kT0);
  REQUIRE_FALSE(mapper.evaluate(kT0).failsafe);

  SECTION("bad CRC") {
    auto w = fw.encoder.next(fp::AxesFrame{0, {0, 100, 0}});
    w.data[0] ^= 0xFF;
    CHECK_FALSE(mapper.on_frame(0, w.can_id, w.data, kT0 + 1000));
    auto s = mapper.evaluate(kT0 + 1000);
    CHECK(s.failsafe);
    CHECK(rise::msgs::has(s.failsafe_causes, rise::msgs::FailsafeCause::ProtectionFailed));
    CHECK(s.sources[0].errors[static_cast<std::size_t>(fp::DecodeError::BadCrc)] == 1);
    CHECK(s.sources[0].frames_bad() == 1);
    // recovery_frames = 3 in the shipped definition: two are not enough.
    fw.feed(fp::ButtonsFrame{1}, kT0 + 2000);
    fw.feed(fp::ButtonsFrame{1}, kT0 + 3000);
    CHECK(mapper.evaluate(kT0 + 3000).failsafe);
    fw.feed(fp::ButtonsFrame{1}, kT0 + 4000);
    CHECK_FALSE(mapper.evaluate(kT0 + 4000).failsafe);
  }
  SECTION("repeated alive counter") {
    const auto w = fw.encoder.next(fp::ButtonsFrame{1});
    mapper.on_frame(0, w.can_id, w.data, kT0 + 1000);
    mapper.on_frame(0, w.can_id, w.data, kT0 + 2000);
    const auto s = mapper.evaluate(kT0 + 2000);
    CHECK(s.failsafe);
    CHECK(s.sources[0].errors[static_cast<std::size_t>(fp::DecodeError::RepeatedCounter)] == 1);
  }
  SECTION("wrong length") {
    const auto w = fw.encoder.next(fp::ButtonsFrame{1});
    mapper.on_frame(0, w.can_id, std::span<const uint8_t>(w.data.data(), 6), kT0 + 1000);
    const auto s = mapper.evaluate(kT0 + 1000);
    CHECK(s.failsafe);
    CHECK(s.sources[0].errors[static_cast<std::size_t>(fp::DecodeError::BadLength)] == 1);
  }
  SECTION("a frame of another node is counted but is no failed check") {
    const uint8_t data[8] = {};
    mapper.on_frame(0, 0x7DF, data, kT0 + 1000);
    const auto s = mapper.evaluate(kT0 + 1000);
    CHECK_FALSE(s.failsafe);
    CHECK(s.sources[0].errors[static_cast<std::size_t>(fp::DecodeError::UnknownId)] == 1);
  }
}

TEST_CASE("releasing the dead-man zeroes every motion control but not the others", "[hil]") {
  PanelMapper mapper(console());
  mapper.on_connection(0, true, kT0);
  Firmware fw{mapper};
  fw.buttons = 1u | (1u << 2);  // dead-man + gripper_open
  fw.axes[1] = fp::axis_from_unit(0.9f);
  fw.axes[2] = fp::axis_from_unit(-0.7f);
  fw.cycle(kT0);
  auto s = mapper.evaluate(kT0);
  REQUIRE(s.deadman);
  CHECK(axis(mapper, s, "drive_y") > 0.8f);
  CHECK(pressed(mapper, s, "gripper_open"));

  fw.buttons = 1u << 2;  // dead-man released, gripper still held
  fw.cycle(kT0 + 10000);
  s = mapper.evaluate(kT0 + 10000);
  CHECK_FALSE(s.failsafe);  // releasing the dead-man is normal operation
  CHECK_FALSE(s.deadman);
  CHECK(axis(mapper, s, "drive_y") == 0.0f);
  CHECK(axis(mapper, s, "arm_x") == 0.0f);
  CHECK_FALSE(pressed(mapper, s, "gripper_open"));
  CHECK(position(mapper, s, "speed") == 2);  // not a motion control
}

TEST_CASE("the e-stop, a console fault, a lost connection and an unreadable axis each make the panel failsafe",
          "[hil]") {
  PanelMapper mapper(console());
  mapper.on_connection(0, true, kT0);
  Firmware fw{mapper};
  fw.buttons = 1;
  fw.axes[1] = fp::axis_from_unit(0.5f);
  fw.cycle(kT0);
  REQUIRE_FALSE(mapper.evaluate(kT0).failsafe);
  std::string expected;
  SECTION("e-stop") {
    fw.buttons = 1u | (1u << 1);
    expected = "e-stop pressed";
  }
  SECTION("console fault") {
    fw.status = fp::PanelStatus::Fault;
    expected = "console status";
  }
  SECTION("axis not available") {
    fw.axes[0] = fp::kAxisInvalid;
    expected = "drive_x: not available";
  }
  SECTION("switch not available") {
    fw.switches[1] = fp::kSwitchInvalid;
    expected = "speed: position not available";
  }
  SECTION("disconnected") {
    mapper.on_connection(0, false, kT0 + 5000);
    expected = "console: disconnected";
  }
  fw.cycle(kT0 + 10000);
  const auto s = mapper.evaluate(kT0 + 10000);
  INFO(s.failsafe_reason);
  CHECK(s.failsafe);
  CHECK(s.failsafe_reason.find(expected) != std::string::npos);
  CHECK(axis(mapper, s, "drive_y") == 0.0f);
}

TEST_CASE("a reconnect is counted and the alive counters start afresh", "[hil]") {
  PanelMapper mapper(console());
  mapper.on_connection(0, true, kT0);
  Firmware fw{mapper};
  fw.cycle(kT0);
  mapper.on_connection(0, false, kT0 + 1000);
  mapper.on_connection(0, true, kT0 + 2000);
  Firmware restarted{mapper};  // a rebooted console counts from 0 again
  restarted.cycle(kT0 + 3000);
  const auto s = mapper.evaluate(kT0 + 3000);
  CHECK(s.sources[0].reconnects == 1);
  CHECK(s.sources[0].frames_bad() == 0);
  CHECK_FALSE(s.sources[0].stale);
}

TEST_CASE("feedback by name becomes LED bits and display values of the console", "[hil]") {
  const auto def = console();
  PanelSnapshot snap;
  snap.failsafe = true;
  snap.controls.resize(def.controls.size());
  rise::hil::FeedbackRequest request;
  request.displays.emplace_back("speed", 0.4251f);
  request.buzzer = fp::BuzzerMode::Beep;
  auto frames = rise::hil::build_feedback(def, 0, request, snap);
  CHECK(frames.indicators.leds_on == 0b011u);  // power + fault (failsafe), no e-stop
  CHECK(frames.indicators.buzzer == fp::BuzzerMode::Beep);
  REQUIRE(frames.displays.size() == 1);
  CHECK(frames.displays[0].raw == 43);  // 0.4251 with 2 decimals
  request.leds.emplace_back("power", false);
  frames = rise::hil::build_feedback(def, 0, request, snap);
  CHECK(frames.indicators.leds_on == 0b010u);
  CHECK(rise::hil::display_raw(1e12f, 2) == INT32_MAX);
}

namespace {
const char* kTransformsPanel = R"(panel: transforms
sources:
  - {name: console, protocol: rise-can-v1, node: 0, timeout_ms: 50}
controls:
  - {name: drive_y, kind: axis, signal: axis.1, expo: 1.0, lowpass_ms: 100, motion: true, safe: 0.0}
  - {name: deadman, kind: button, signal: button.0, role: deadman, safe: false}
  - {name: lights, kind: button, signal: button.2, mode: toggle, safe: false}
  - {name: horn, kind: button, signal: button.3, mode: long_press, long_press_ms: 500, safe: false}
  - {name: camera, kind: switch, bits: [button.4, button.5, button.6], encoding: one_hot,
     positions: [front, arm, rear], safe: front}
)";

struct TransformFirmware {
  PanelMapper& mapper;
  fp::Encoder encoder{0};
  int16_t drive_y = 0;
  uint32_t buttons = 0;
  void cycle(int64_t t) {
    auto feed = [&](const fp::Message& m) {
      const auto w = encoder.next(m);
      mapper.on_frame(0, w.can_id, w.data, t);
    };
    feed(fp::HeartbeatFrame{fp::kProtocolVersion, fp::PanelStatus::Operational, 0});
    feed(fp::AxesFrame{0, {0, drive_y, 0}});
    feed(fp::ButtonsFrame{buttons});
  }
};
}  // namespace

TEST_CASE("per-control transforms from the definition: expo, low-pass ramp, toggle, long press, switch from bits",
          "[hil]") {
  PanelMapper mapper(rise::panels::parse_panel_definition(kTransformsPanel, "t.yaml"));
  mapper.on_connection(0, true, kT0);
  TransformFirmware fw{mapper};
  const auto& def = mapper.definition();
  auto value = [&](const PanelSnapshot& s, const char* name) { return s.controls[*def.find_control(name)]; };

  fw.buttons = 1u | (1u << 4);  // dead-man, camera = front
  fw.drive_y = fp::axis_from_unit(0.5f);
  fw.cycle(kT0);
  auto s = mapper.evaluate(kT0);
  INFO(s.failsafe_reason);
  REQUIRE_FALSE(s.failsafe);
  // The low-pass restarts from the safe value: no jump at the first reading.
  CHECK(value(s, "drive_y").axis == 0.0f);
  // One time constant later: 63 % of the cubic-expo value 0.125.
  for (int64_t t = kT0 + 10'000; t <= kT0 + 100'000; t += 10'000) {
    fw.cycle(t);
    s = mapper.evaluate(t);
  }
  CHECK(value(s, "drive_y").axis == Approx(0.125 * (1 - std::exp(-1.0))).margin(2e-3));
  CHECK(value(s, "camera").position == 0);

  // Toggle: press and release → latched on.
  fw.buttons |= 1u << 2;
  fw.cycle(kT0 + 110'000);
  mapper.evaluate(kT0 + 110'000);
  fw.buttons &= ~(1u << 2);
  fw.cycle(kT0 + 120'000);
  s = mapper.evaluate(kT0 + 120'000);
  CHECK(value(s, "lights").pressed);

  // Camera rotary switch: between detents (no contact) it keeps "front";
  // on the "rear" contact it reads rear.
  fw.buttons &= ~(1u << 4);
  fw.cycle(kT0 + 130'000);
  CHECK(value(mapper.evaluate(kT0 + 130'000), "camera").position == 0);
  fw.buttons |= 1u << 6;
  fw.cycle(kT0 + 140'000);
  CHECK(value(mapper.evaluate(kT0 + 140'000), "camera").position == 2);

  // Long press: held 400 ms → not yet; 500 ms → yes.
  fw.buttons |= 1u << 3;
  for (int64_t t = kT0 + 150'000; t <= kT0 + 550'000; t += 20'000) {
    fw.cycle(t);
    s = mapper.evaluate(t);
  }
  CHECK_FALSE(value(s, "horn").pressed);
  fw.cycle(kT0 + 650'000);
  CHECK(value(mapper.evaluate(kT0 + 650'000), "horn").pressed);

  // The source goes stale: everything safe; when it returns the toggle has
  // forgotten its latched state.
  s = mapper.evaluate(kT0 + 800'000);
  REQUIRE(s.failsafe);
  CHECK_FALSE(value(s, "lights").pressed);
  fw.cycle(kT0 + 810'000);
  s = mapper.evaluate(kT0 + 810'000);
  CHECK_FALSE(s.failsafe);
  CHECK_FALSE(value(s, "lights").pressed);
}

TEST_CASE("transform keys are checked with file:line and the key", "[hil]") {
  auto error_of = [](std::string text) {
    try {
      rise::panels::parse_panel_definition(text, "t.yaml");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string base = kTransformsPanel;
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string t = base;
    t.replace(t.find(from), from.size(), to);
    return t;
  };
  CHECK_THAT(error_of(replaced("expo: 1.0", "expo: 2")), Catch::StartsWith("t.yaml:5: controls.drive_y.expo: must be in 0..1"));
  CHECK_THAT(error_of(replaced("mode: toggle", "mode: latch")), Catch::StartsWith("t.yaml:7: controls.lights.mode: unknown mode 'latch'"));
  CHECK_THAT(error_of(replaced("button.5, button.6]", "button.5]")),
             Catch::StartsWith("t.yaml:9: controls.camera.bits: one_hot needs one bit per position"));
  CHECK_THAT(error_of(replaced("button.6]", "button.2]")),
             Catch::StartsWith("t.yaml:9: controls.camera.bits: signal 'button.2' is already bound"));
  CHECK_THAT(error_of(replaced("role: deadman, safe: false", "role: deadman, mode: toggle, safe: false")),
             Catch::StartsWith("t.yaml:6: controls.deadman.mode: the deadman must be mode: direct"));
}

TEST_CASE("a CAN bus-off makes the source failsafe until the controller reports its restart", "[hil]") {
  PanelMapper mapper(console());
  mapper.on_connection(0, true, kT0);
  Firmware fw{mapper};
  fw.buttons = 1u << 0;
  fw.axes[1] = fp::axis_from_unit(0.5f);
  fw.cycle(kT0);
  REQUIRE_FALSE(mapper.evaluate(kT0 + 1000).failsafe);

  rise::hil::io::CanErrorReport report;
  SECTION("error-warning and error-passive are reported, the panel stays usable") {
    report.classes = 0x004;
    report.state = rise::hil::io::CanBusState::Passive;
    CHECK(mapper.on_bus_error(0, report, kT0 + 2000));
    CHECK_FALSE(mapper.on_bus_error(0, report, kT0 + 2500));  // no change
    const auto s = mapper.evaluate(kT0 + 3000);
    CHECK_FALSE(s.failsafe);
    CHECK(s.sources[0].bus_state == rise::hil::io::CanBusState::Passive);
    CHECK(s.sources[0].error_frames == 2);
  }
  SECTION("bus-off holds through valid frames and ends at the restart") {
    report.classes = 0x040;
    report.state = rise::hil::io::CanBusState::BusOff;
    CHECK(mapper.on_bus_error(0, report, kT0 + 2000));
    auto s = mapper.evaluate(kT0 + 3000);
    CHECK(s.failsafe);
    CHECK(s.failsafe_reason == "console: CAN bus-off");
    CHECK(axis(mapper, s, "drive_y") == 0.0f);
    CHECK(s.sources[0].bus_offs == 1);
    for (int i = 1; i <= 5; ++i) fw.cycle(kT0 + 3000 + i * 10'000);
    CHECK(mapper.evaluate(kT0 + 55'000).failsafe);

    report.classes = 0x100;  // CAN_ERR_RESTARTED
    report.state = rise::hil::io::CanBusState::Active;
    CHECK(mapper.on_bus_error(0, report, kT0 + 56'000));
    s = mapper.evaluate(kT0 + 57'000);
    INFO(s.failsafe_reason);
    CHECK_FALSE(s.failsafe);
    CHECK(axis(mapper, s, "drive_y") == Approx(0.5).margin(0.05));
  }
  SECTION("an error frame without a state (a bus error) is only counted") {
    report.classes = 0x088;  // protocol violation + bus error
    CHECK_FALSE(mapper.on_bus_error(0, report, kT0 + 2000));
    const auto s = mapper.evaluate(kT0 + 3000);
    CHECK_FALSE(s.failsafe);
    CHECK(s.sources[0].error_frames == 1);
    CHECK(s.sources[0].bus_state == rise::hil::io::CanBusState::Active);
  }
}

TEST_CASE("a source that is down carries why until it connects, and a bus that never opened reports no state",
          "[hil]") {
  PanelMapper mapper(console());
  const auto definition = mapper.definition();
  const auto health = [&](int64_t t) {
    return rise::hil::to_message(definition, mapper.evaluate(t), "t1", 0, t, {"socketcand://h:1/can0"}).sources.at(0);
  };
  SECTION("never connected") {
    mapper.on_connection(0, false, kT0);
    auto h = health(kT0);
    CHECK(h.down_reason == "not connected yet");
    CHECK(h.bus_state.empty());  // no controller state to report
    CHECK(h.status.empty());     // no heartbeat heard
    CHECK(h.last_frame_age_us < 0);
    mapper.on_connection(0, false, kT0, "socketcand://h:1/can0: cannot resolve host 'h': Name or service not known");
    h = health(kT0);
    CHECK(h.down_reason == "socketcand://h:1/can0: cannot resolve host 'h': Name or service not known");
    CHECK_FALSE(h.connected);
  }
  SECTION("connected, then lost with a reason, then back") {
    mapper.on_connection(0, true, kT0);
    auto h = health(kT0);
    CHECK(h.down_reason.empty());
    CHECK(h.bus_state == "error-active");
    mapper.on_connection(0, false, kT0 + 1000, "socketcand://h:1/can0: recv: Connection reset by peer");
    CHECK(health(kT0 + 1000).down_reason == "socketcand://h:1/can0: recv: Connection reset by peer");
    mapper.on_connection(0, false, kT0 + 2000);  // a retry without a new reason keeps the old one
    CHECK(health(kT0 + 2000).down_reason == "socketcand://h:1/can0: recv: Connection reset by peer");
    mapper.on_connection(0, true, kT0 + 3000);
    CHECK(health(kT0 + 3000).down_reason.empty());
  }
}
