// A third-party Modbus device as a panel source (protocol modbus,
// panels/definitions/modbus_plc_panel.yaml): its definition, the poll of
// its tables, the mapping of its points, its feedback writes, and the
// bridge polling our libmodbus server as the device over real TCP, with
// the session recorded and verified.

#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include "hil/feedback.hpp"
#include "hil/modbus_poll.hpp"
#include "hil/panel_state_message.hpp"
#include "hil/replay_verify.hpp"
#include "hil/session_recorder.hpp"
#include "hil/source_factory.hpp"
#include "msgs/channels.hpp"
#include "msgs/clock.hpp"
#include "tests/hil/bridge_test_support.hpp"

using namespace rise::hil;
using rise::hil::test::Published;
using rise::hil::io::ModbusFunction;
using rise::panels::ModbusPoint;
using rise::panels::ModbusTable;

namespace {

rise::panels::PanelDefinition plc_panel() {
  return rise::panels::load_panel_definition(std::string(RISE_SOURCE_DIR) +
                                             "/panels/definitions/modbus_plc_panel.yaml");
}

std::size_t control(const rise::panels::PanelDefinition& def, const char* name) { return *def.find_control(name); }

// A definition of one modbus source with a dead-man on discrete input 0,
// `control` on line 6 and `feedback` on line 8.
std::string definition(const std::string& source, const std::string& control, const std::string& feedback) {
  return "panel: p\n"
         "sources:\n"
         "  - " + source + "\n"
         "controls:\n"
         "  - {name: deadman, kind: button, signal: discrete_input.0, role: deadman, safe: false}\n"
         "  - " + control + "\n"
         "feedback:\n"
         "  " + feedback + "\n";
}

const std::string kSource = "{name: plc, protocol: modbus, unit: 1, poll_hz: 50, timeout_ms: 100}";
const std::string kButton = "{name: x, kind: button, signal: discrete_input.1, safe: false}";
const std::string kLeds = "leds: [{name: fault, signal: coil.3}]";

// A link that answers nothing and keeps every write it is given.
class WriteLog final : public rise::hil::io::ModbusLink {
 public:
  struct Write {
    ModbusFunction function;
    uint16_t address;
    uint16_t value;
  };
  std::vector<Write> writes;
  rise::hil::io::ModbusResult read_coils(uint16_t, std::span<uint8_t>) override { return error(); }
  rise::hil::io::ModbusResult read_discrete_inputs(uint16_t, std::span<uint8_t>) override { return error(); }
  rise::hil::io::ModbusResult read_holding_registers(uint16_t, std::span<uint16_t>) override { return error(); }
  rise::hil::io::ModbusResult read_input_registers(uint16_t, std::span<uint16_t>) override { return error(); }
  rise::hil::io::ModbusResult write_coils(uint16_t address, std::span<const uint8_t> bits) override {
    for (std::size_t i = 0; i < bits.size(); ++i)
      writes.push_back({ModbusFunction::WriteMultipleCoils, static_cast<uint16_t>(address + i), bits[i]});
    return {};
  }
  rise::hil::io::ModbusResult write_registers(uint16_t address, std::span<const uint16_t> registers) override {
    for (std::size_t i = 0; i < registers.size(); ++i)
      writes.push_back({ModbusFunction::WriteMultipleRegisters, static_cast<uint16_t>(address + i), registers[i]});
    return {};
  }
  bool is_open() const override { return true; }
  rise::hil::io::ModbusStatus reopen() override { return rise::hil::io::ModbusStatus::Ok; }
  void close() override {}

 private:
  static rise::hil::io::ModbusResult error() { return {rise::hil::io::ModbusStatus::Error, 0}; }
};

std::string temp_dir(const std::string& name) {
  return std::filesystem::temp_directory_path() / (name + "-" + std::to_string(::getpid()));
}

}  // namespace

TEST_CASE("modbus points name a table, an address and a register's bit, and read back as written", "[hil]") {
  SECTION("good") {
    const auto [text, kind, address, bit] = GENERATE(table<std::string, ModbusTable, int, int>({
        {"coil.0", ModbusTable::Coils, 0, -1},
        {"discrete_input.17", ModbusTable::DiscreteInputs, 17, -1},
        {"holding_register.65535", ModbusTable::HoldingRegisters, 65535, -1},
        {"input_register.5.bit.15", ModbusTable::InputRegisters, 5, 15},
        {"holding_register.3.bit.0", ModbusTable::HoldingRegisters, 3, 0},
    }));
    const auto p = rise::panels::parse_modbus_point(text);
    REQUIRE(p.has_value());
    CHECK(p->table == kind);
    CHECK(p->address == address);
    CHECK(p->bit == bit);
    CHECK(p->is_bit() == (bit >= 0 || p->bit_table()));
    CHECK(rise::panels::to_string(*p) == text);
  }
  SECTION("bad") {
    const std::string text = GENERATE("coil", "coil.", "coil.65536", "coil.1.bit.0", "input_register.2.bit.16",
                                      "input_register.-1", "input_register.2.bit.", "register.4", "axis.0",
                                      "holding_register.1.bits.2");
    INFO(text);
    CHECK_FALSE(rise::panels::parse_modbus_point(text).has_value());
  }
}

TEST_CASE("a modbus source's definition binds points of the device's tables and refuses every mistake with "
          "file:line: key: what",
          "[hil]") {
  SECTION("the shipped example") {
    const auto def = plc_panel();
    REQUIRE(def.sources.size() == 1);
    CHECK(def.sources[0].is_generic_modbus());
    CHECK(def.sources[0].is_modbus());
    CHECK(def.sources[0].timeout_ms == 100);
    const auto& drive_x = def.controls[control(def, "drive_x")];
    CHECK(drive_x.modbus_point == ModbusPoint{ModbusTable::InputRegisters, 0, -1});
    CHECK(drive_x.modbus_type == rise::panels::ModbusValueType::Int16);
    CHECK(drive_x.range_min == -1000.0);
    CHECK(drive_x.range_max == 1000.0);
    CHECK(def.controls[control(def, "lift")].modbus_type == rise::panels::ModbusValueType::UInt16);
    CHECK(def.controls[control(def, "estop")].modbus_point == ModbusPoint{ModbusTable::InputRegisters, 5, 0});
    CHECK(def.controls[control(def, "speed")].modbus_point == ModbusPoint{ModbusTable::HoldingRegisters, 3, -1});
    REQUIRE(def.leds.size() == 3);
    CHECK(def.leds[1].modbus_point == ModbusPoint{ModbusTable::Coils, 3, -1});
    CHECK(def.leds[2].modbus_point == ModbusPoint{ModbusTable::HoldingRegisters, 12, -1});
    REQUIRE(def.displays.size() == 1);
    CHECK(def.displays[0].modbus_point == ModbusPoint{ModbusTable::HoldingRegisters, 10, -1});
    CHECK(def.displays[0].decimals == 2);
  }
  SECTION("mistakes") {
    const auto [source, control_yaml, feedback, message] =
        GENERATE_REF(table<std::string, std::string, std::string, std::string>({
            {"{name: plc, protocol: modbus, recovery_frames: 3}", kButton, kLeds,
             "p.yaml:3: sources[0].recovery_frames: not used by protocol modbus (no alive counter or CRC: stale "
             "when no poll is answered within timeout_ms)"},
            {kSource, "{name: x, kind: axis, signal: input_register.70000, range: [0, 10], safe: 0.0}", kLeds,
             "p.yaml:6: controls.x.signal: unknown signal 'input_register.70000' (input_register.N, "
             "holding_register.N, discrete_input.N, coil.N, input_register.N.bit.B, holding_register.N.bit.B; N "
             "0..65535, B 0..15)"},
            {kSource, "{name: x, kind: button, signal: button.1, safe: false}", kLeds,
             "p.yaml:6: controls.x.signal: unknown signal 'button.1'"},
            {kSource, "{name: x, kind: axis, signal: input_register.4, safe: 0.0}", kLeds,
             "p.yaml:6: controls.x.range: missing: an axis of a modbus source maps range: [min, max] to -1..1"},
            {kSource, "{name: x, kind: axis, signal: input_register.5.bit.2, range: [0, 1], safe: 0.0}", kLeds,
             "p.yaml:6: controls.x.signal: an axis reads a whole register (input_register.N, holding_register.N), "
             "not input_register.5.bit.2"},
            {kSource, "{name: x, kind: axis, signal: input_register.4, range: [-100, 100], safe: 0.0}", kLeds,
             "p.yaml:6: controls.x.range: outside what a register holds as uint16 (0..65535); type: int16 reads it "
             "signed"},
            {kSource, "{name: x, kind: axis, signal: input_register.4, type: int16, range: [0, 40000], safe: 0.0}",
             kLeds, "p.yaml:6: controls.x.range: outside what a register holds as int16 (-32768..32767)"},
            {kSource, "{name: x, kind: axis, signal: input_register.4, range: [10, 10], safe: 0.0}", kLeds,
             "p.yaml:6: controls.x.range: needs min < max"},
            {kSource, "{name: x, kind: axis, signal: input_register.4, range: 10, safe: 0.0}", kLeds,
             "p.yaml:6: controls.x.range: expected [min, max]"},
            {kSource, "{name: x, kind: axis, signal: input_register.4, type: float, range: [0, 9], safe: 0.0}", kLeds,
             "p.yaml:6: controls.x.type: unknown type 'float' (uint16, int16)"},
            {kSource, "{name: x, kind: button, signal: input_register.4, type: int16, safe: false}", kLeds,
             "p.yaml:6: controls.x.type: not used by a button (pressed while the register is not 0)"},
            {kSource, "{name: x, kind: button, signal: coil.4, type: int16, safe: false}", kLeds,
             "p.yaml:6: controls.x.type: coil.4 is one bit: only a whole register has a type"},
            {kSource, "{name: x, kind: button, signal: coil.4, range: [0, 1], safe: false}", kLeds,
             "p.yaml:6: controls.x.range: only for an axis"},
            {kSource, "{name: x, kind: switch, bits: [coil.1, coil.2], positions: [a, b], safe: a}", kLeds,
             "p.yaml:6: controls.x.bits: not for a modbus source: bind the register whose value is the position"},
            {kSource, "{name: x, kind: switch, signal: coil.2, positions: [a, b, c], safe: a}", kLeds,
             "p.yaml:6: controls.x.signal: coil.2 is one bit: two positions at most (a register holds more)"},
            {kSource, "{name: x, kind: button, signal: discrete_input.0, safe: false}", kLeds,
             "p.yaml:6: controls.x.signal: signal already bound to another control"},
            {kSource, "{name: x, kind: button, signal: discrete_input.2000, safe: false}", kLeds,
             "p.yaml:6: controls.x.signal: discrete_input.2000 makes the poll read discrete_inputs 0..2000 (2001), "
             "more than one request reads (2000)"},
            {kSource, "{name: x, kind: button, signal: coil.3, safe: false}", kLeds,
             "p.yaml:6: controls.x.signal: coil.3 is written by the LED 'fault': a control cannot read it"},
            {kSource, "{name: x, kind: button, signal: holding_register.10.bit.1, safe: false}",
             "displays: [{name: speed, signal: holding_register.10}]",
             "p.yaml:6: controls.x.signal: holding_register.10.bit.1 is written by the display 'speed': a control "
             "cannot read it"},
            {kSource, kButton, "leds: [{name: fault, bit: 3}]",
             "p.yaml:8: feedback.leds.fault.bit: a modbus source's LED is a coil or a holding register: signal: "
             "coil.N"},
            {kSource, kButton, "leds: [{name: fault, signal: discrete_input.3}]",
             "p.yaml:8: feedback.leds.fault.signal: discrete_input.3 cannot be written: an LED is a coil.N or a "
             "holding_register.N (written 1 / 0)"},
            {kSource, kButton, "leds: [{name: fault, signal: holding_register.2.bit.1}]",
             "p.yaml:8: feedback.leds.fault.signal: holding_register.2.bit.1 cannot be written"},
            {kSource, kButton, "leds: [{name: a, signal: coil.1}, {name: b, signal: coil.1}]",
             "p.yaml:8: feedback.leds.b.signal: coil.1 is already written by another LED or display"},
            {kSource, kButton, "displays: [{name: speed, index: 0}]",
             "p.yaml:8: feedback.displays.speed.index: a modbus source's display is a holding register: signal: "
             "holding_register.N"},
            {kSource, kButton, "displays: [{name: speed, signal: coil.1}]",
             "p.yaml:8: feedback.displays.speed.signal: coil.1 cannot be written: a display is a holding_register.N"},
            {kSource, kButton, "displays: [{name: speed, signal: holding_register.1, type: int32}]",
             "p.yaml:8: feedback.displays.speed.type: unknown type 'int32' (uint16, int16)"},
            {kSource, kButton, "buzzer: {source: plc}",
             "p.yaml:8: feedback.buzzer.source: a modbus source has no buzzer (light an LED on its coil instead)"},
        }));
    INFO(control_yaml << " / " << feedback);
    try {
      rise::panels::parse_panel_definition(definition(source, control_yaml, feedback), "p.yaml");
      FAIL("accepted");
    } catch (const std::runtime_error& e) {
      CHECK_THAT(e.what(), Catch::StartsWith(message));
    }
  }
  SECTION("a modbus source that no control reads has nothing to poll: refused") {
    const std::string yaml =
        "panel: p\n"
        "sources:\n"
        "  - {name: console, protocol: rise-modbus-v1}\n"
        "  - {name: plc, protocol: modbus}\n"
        "controls:\n"
        "  - {name: deadman, kind: button, source: console, signal: button.0, safe: false}\n"
        "feedback:\n"
        "  leds: [{name: fault, source: plc, signal: coil.3}]\n";
    CHECK_THROWS_WITH(rise::panels::parse_panel_definition(yaml, "p.yaml"),
                      "p.yaml:4: sources[1]: no control reads source 'plc': a modbus source is trusted while its "
                      "polls are answered, and it needs a point to poll");
  }
  SECTION("a point's signal and type are refused on a source of another protocol") {
    const std::string head =
        "panel: p\n"
        "sources:\n"
        "  - {name: console, protocol: rise-modbus-v1}\n"
        "controls:\n";
    CHECK_THROWS_WITH(rise::panels::parse_panel_definition(
                          head + "  - {name: deadman, kind: button, signal: button.0, type: int16, safe: false}\n",
                          "p.yaml"),
                      "p.yaml:5: controls.deadman.type: only for controls of a modbus source");
    CHECK_THROWS_WITH(rise::panels::parse_panel_definition(
                          head + "  - {name: deadman, kind: button, signal: button.0, safe: false}\n"
                                 "feedback:\n"
                                 "  displays: [{name: speed, signal: holding_register.1}]\n",
                          "p.yaml"),
                      "p.yaml:7: feedback.displays.speed.signal: only for a display of a modbus source (here: index: "
                      "0..255)");
  }
}

TEST_CASE("a modbus source's poll reads each used table's span in one request, and its points become axes, "
          "buttons and switches",
          "[hil]") {
  const auto def = plc_panel();
  const auto reads = modbus_poll_reads(def, 0);
  // Function-code order; coils are only written (LEDs), so not read.
  REQUIRE(reads.size() == 3);
  CHECK((reads[0].function == ModbusFunction::ReadDiscreteInputs && reads[0].address == 0 && reads[0].count == 2));
  CHECK((reads[1].function == ModbusFunction::ReadHoldingRegisters && reads[1].address == 3 && reads[1].count == 1));
  CHECK((reads[2].function == ModbusFunction::ReadInputRegisters && reads[2].address == 0 && reads[2].count == 6));

  ModbusPoll poll(reads);
  auto answer = [&](uint16_t di, uint16_t speed, std::vector<uint16_t> ir) {
    poll.store(0, std::vector<uint16_t>{static_cast<uint16_t>(di & 1u), static_cast<uint16_t>((di >> 1) & 1u)});
    poll.store(1, std::vector<uint16_t>{speed});
    poll.store(2, ir);
  };
  PanelMapper mapper(def);
  mapper.on_connection(0, true, 1000);
  auto snap = mapper.evaluate(1000);
  CHECK(snap.failsafe_reason == "plc: no poll answered yet");
  CHECK(snap.sources[0].stale);

  // drive_x -500 of ±1000 (int16), drive_y full, lift 4095 of 0..4095, status word 0b1000.
  answer(0b01, 2, {static_cast<uint16_t>(-500), 1000, 4095, 0, 0, 0b1000});
  CHECK(mapper.on_modbus_poll(0, poll, 2000));
  CHECK_FALSE(mapper.on_modbus_poll(0, poll, 3000));  // the same values: no change
  snap = mapper.evaluate(3000);
  INFO(snap.failsafe_reason);
  REQUIRE_FALSE(snap.failsafe);
  CHECK(snap.controls[control(def, "drive_x")].axis == Approx(-(0.5 - 0.05) / 0.95).margin(1e-5));
  CHECK(snap.controls[control(def, "drive_y")].axis == Approx(1.0).margin(1e-6));
  CHECK(snap.controls[control(def, "lift")].axis == Approx(1.0).margin(1e-6));
  CHECK(snap.controls[control(def, "deadman")].pressed);
  CHECK_FALSE(snap.controls[control(def, "horn")].pressed);
  CHECK_FALSE(snap.controls[control(def, "estop")].pressed);
  CHECK(snap.controls[control(def, "speed")].position == 2);
  CHECK(snap.sources[0].frames_ok == 2);

  SECTION("a register's bit is a button, a register beyond the positions fails the switch safe") {
    answer(0b11, 1, {0, 0, 2048, 0, 0, 0b1000});
    CHECK(mapper.on_modbus_poll(0, poll, 4000));
    snap = mapper.evaluate(4000);
    CHECK(snap.controls[control(def, "horn")].pressed);
    CHECK(snap.controls[control(def, "lift")].axis == Approx(2.0 * 2048 / 4095 - 1.0).margin(1e-5));
    CHECK(snap.controls[control(def, "speed")].position == 1);
    answer(0b11, 7, {0, 0, 2048, 0, 0, 0b1001});
    CHECK(mapper.on_modbus_poll(0, poll, 5000));
    snap = mapper.evaluate(5000);
    CHECK(snap.controls[control(def, "estop")].pressed);
    CHECK(snap.failsafe_reason == "speed: position 7 unknown; e-stop pressed");
    CHECK(snap.controls[control(def, "speed")].position == 0);  // slow, its safe value
    CHECK(snap.controls[control(def, "lift")].axis == -1.0f);   // a motion control, safe while failsafe
  }
  SECTION("no answered poll for timeout_ms: stale, every control at its safe value") {
    snap = mapper.evaluate(3000 + 100'000);
    CHECK_FALSE(snap.failsafe);
    snap = mapper.evaluate(3000 + 100'001);
    CHECK(snap.failsafe_reason == "plc: stale (no poll answered for 100 ms)");
    CHECK(snap.sources[0].stale);
    CHECK(snap.controls[control(def, "lift")].axis == -1.0f);
    CHECK(snap.controls[control(def, "drive_x")].axis == 0.0f);
    CHECK(snap.controls[control(def, "speed")].position == 0);
  }
  SECTION("a lost link: disconnected at once, and no poll answered since until the next one") {
    mapper.on_connection(0, false, 4000);
    CHECK(mapper.evaluate(4000).failsafe_reason == "plc: disconnected");
    mapper.on_connection(0, true, 5000);
    CHECK(mapper.evaluate(5000).failsafe_reason == "plc: no poll answered yet");
    CHECK(mapper.on_modbus_poll(0, poll, 6000));
    CHECK_FALSE(mapper.evaluate(6000).failsafe);
  }
}

TEST_CASE("a modbus source's LEDs and displays are written point by point, each only when it changes", "[hil]") {
  const auto def = plc_panel();
  PanelSnapshot healthy;
  healthy.failsafe = false;
  healthy.controls.resize(def.controls.size());
  FeedbackRequest request;
  request.leds.emplace_back("beacon", true);
  request.displays.emplace_back("speed", 1.25f);

  const auto writes = build_modbus_feedback(def, 0, request, healthy);
  REQUIRE(writes.size() == 4);  // power, fault, beacon, speed
  WriteLog link;
  ModbusFeedbackWriter writer;
  REQUIRE(writer.write(link, writes).ok());
  REQUIRE(link.writes.size() == 4);
  CHECK((link.writes[0].function == ModbusFunction::WriteMultipleCoils && link.writes[0].address == 0 &&
         link.writes[0].value == 1));  // power
  CHECK((link.writes[1].function == ModbusFunction::WriteMultipleCoils && link.writes[1].address == 3 &&
         link.writes[1].value == 0));  // fault: the panel is healthy
  CHECK((link.writes[2].function == ModbusFunction::WriteMultipleRegisters && link.writes[2].address == 12 &&
         link.writes[2].value == 1));  // beacon
  CHECK((link.writes[3].function == ModbusFunction::WriteMultipleRegisters && link.writes[3].address == 10 &&
         link.writes[3].value == 125));  // 1.25 at 2 decimals

  REQUIRE(writer.write(link, build_modbus_feedback(def, 0, request, healthy)).ok());
  CHECK(link.writes.size() == 4);  // nothing changed, nothing written

  request.displays[0].second = -0.5f;
  PanelSnapshot failsafe = healthy;
  failsafe.failsafe = true;
  REQUIRE(writer.write(link, build_modbus_feedback(def, 0, request, failsafe)).ok());
  REQUIRE(link.writes.size() == 6);
  CHECK((link.writes[4].address == 3 && link.writes[4].value == 1));  // fault lit
  CHECK((link.writes[5].address == 10 && static_cast<int16_t>(link.writes[5].value) == -50));  // int16

  request.displays[0].second = 400.0f;  // 40000 does not fit an int16
  CHECK(build_modbus_feedback(def, 0, request, failsafe).back().value == 32767);

  writer.forget();  // after a reconnect, everything again
  REQUIRE(writer.write(link, build_modbus_feedback(def, 0, request, failsafe)).ok());
  CHECK(link.writes.size() == 10);
}

TEST_CASE("the bridge polls a third-party Modbus device over TCP, writes its feedback, fails safe when it goes "
          "away and recovers when it returns, and the recorded session verifies",
          "[hil]") {
  const auto def = plc_panel();
  const rise::hil::io::ModbusTableSizes sizes{16, 16, 16, 16};
  auto device = std::make_unique<rise::hil::io::ModbusServer>("modbus+tcp-listen://127.0.0.1:0?unit=1", sizes);
  const uint16_t port = device->port();
  auto serve = [&](rise::hil::io::ModbusServer& d, int16_t drive_y) {
    d.set_input_registers(0, std::vector<uint16_t>{0, static_cast<uint16_t>(drive_y), 0, 0, 0, 0});
    d.set_discrete_inputs(0, std::vector<uint8_t>{1, 0});
    d.set_holding_registers(3, std::vector<uint16_t>{1});
  };
  serve(*device, 600);
  const std::string dir = temp_dir("rise-modbus-device");
  std::filesystem::remove_all(dir);
  const std::string channel = rise::msgs::panel_state_channel("dev");
  const auto drive_y = control(def, "drive_y"), speed = control(def, "speed");
  Published published;
  {
    SessionRecorder recorder(dir);
    std::vector<std::unique_ptr<SourceTransport>> transports;
    transports.push_back(
        rise::hil::open_source(def, 0, "modbus+tcp://127.0.0.1:" + std::to_string(port) + "?unit=1&timeout_ms=50"));
    REQUIRE(recorder.record_source("plc", *transports[0], 1));
    int64_t seq = 0;
    Bridge bridge(def, std::move(transports), [&](const PanelSnapshot& snap) {
      recorder.record_message(channel, to_message(def, snap, "dev", seq++, rise::msgs::wall_us(), {}));
      published.add(snap);
    });
    bridge.start();
    const float expected_y = (0.6f - 0.05f) / 0.95f;
    const auto live = published.wait_for([&](const PanelSnapshot& s) { return !s.failsafe && s.deadman; }, 5000);
    REQUIRE(live.has_value());
    CHECK(live->controls[drive_y].axis == Approx(expected_y).margin(1e-4));
    CHECK(live->controls[speed].position == 1);

    // The device's own logic moves a point: the next poll carries it.
    device->set_holding_registers(3, std::vector<uint16_t>{2});
    CHECK(published.wait_for([&](const PanelSnapshot& s) { return s.controls[speed].position == 2; }, 2000));

    FeedbackRequest request;
    request.displays.emplace_back("speed", 1.25f);
    bridge.set_feedback(request);
    std::array<uint16_t, 16> holding{};
    std::array<uint8_t, 4> coils{};
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(3);
    while (std::chrono::steady_clock::now() < deadline) {
      device->holding_registers(holding);
      if (holding[10] == 125) break;
      std::this_thread::yield();
    }
    device->coils(0, coils);
    CHECK(holding[10] == 125);
    CHECK(holding[12] == 0);     // beacon dark
    CHECK(holding[3] == 2);      // the device's own register, not touched by the feedback
    CHECK(coils[0] == 1);        // power
    CHECK(coils[3] == 0);        // fault: healthy
    CHECK(device->writes_served() == 5);  // one request per point after the first poll, then the display's change

    // The device goes away: failsafe within a poll and a publish period.
    const std::size_t before = published.size();
    device.reset();
    const auto lost = published.wait_for([](const PanelSnapshot& s) { return s.failsafe; }, 3000, before);
    REQUIRE(lost.has_value());
    CHECK(lost->controls[drive_y].axis == 0.0f);
    const int64_t poll_period_us = static_cast<int64_t>(1e6 / def.sources[0].poll_hz);
    CHECK(lost->sources[0].last_frame_age_us <= poll_period_us + def.publish_period_us() + 15000);
    // (A reconnect may slip into the server's last moments: "no poll answered yet" first.)
    CHECK(published.wait_for([](const PanelSnapshot& s) { return s.failsafe_reason == "plc: disconnected"; }, 3000,
                             before));

    // Back on the same port, with fresh tables: reconnected and written again.
    device = std::make_unique<rise::hil::io::ModbusServer>("modbus+tcp-listen://127.0.0.1:" + std::to_string(port) + "?unit=1",
                                                      sizes);
    serve(*device, -600);
    const std::size_t lost_at = published.size();
    const auto back = published.wait_for(
        [&](const PanelSnapshot& s) { return !s.failsafe && s.controls[drive_y].axis < -0.5f; }, 5000, lost_at);
    REQUIRE(back.has_value());
    CHECK(back->sources[0].reconnects >= 1);
    const auto rewritten = std::chrono::steady_clock::now() + std::chrono::seconds(3);
    while (std::chrono::steady_clock::now() < rewritten && device->writes_served() < 4) std::this_thread::yield();
    device->holding_registers(holding);
    CHECK(holding[10] == 125);
    bridge.stop();
    CHECK(recorder.counts().write_errors == 0);
  }
  // The trace holds the device's function codes, and replays to what the bridge published.
  std::ifstream trace(dir + "/plc.modbus.log");
  std::stringstream text;
  text << trace.rdbuf();
  CHECK(text.str().find(" fc=02 addr=0 count=2 ") != std::string::npos);
  CHECK(text.str().find(" fc=03 addr=3 count=1 ") != std::string::npos);
  CHECK(text.str().find(" fc=04 addr=0 count=6 ") != std::string::npos);
  CHECK(text.str().find(" fc=16 addr=10 count=1 ") != std::string::npos);
  const PanelStateLog golden = read_panel_state_log(dir + "/panel_state.lcmlog");
  const VerifyReport report = verify_replay(def, captures_in(def, dir), golden.messages);
  if (report.difference) INFO(describe(*report.difference));
  CHECK(report.passed());
  CHECK(report.messages == golden.messages.size());

  // A definition that polls other points than the recorded ones is refused at the first read it lacks.
  std::ifstream in(std::string(RISE_SOURCE_DIR) + "/panels/definitions/modbus_plc_panel.yaml");
  std::stringstream yaml;
  yaml << in.rdbuf();
  std::string other = yaml.str();
  other.replace(other.find("input_register.5.bit.3"), 22, "input_register.7.bit.3");
  const auto other_def = rise::panels::parse_panel_definition(other, "other.yaml");
  CHECK_THROWS_WITH(verify_replay(other_def, captures_in(other_def, dir), golden.messages),
                    Catch::Contains("/plc.modbus.log:") &&
                        Catch::Contains(": fc=04 addr=0 count=6 is not a read of this source's poll (fc=02 addr=0 "
                                        "count=2, fc=03 addr=3 count=1, fc=04 addr=0 count=8)"));
  std::filesystem::remove_all(dir);
}
