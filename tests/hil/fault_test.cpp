// Input faults in the mapper (between decode and the transforms) with
// explicit times, and wire faults in the transport decorators: frames of the
// console's firmware cross a real in-process bus (mem://) and a real
// libmodbus TCP link through the decorators.

#include <catch2/catch.hpp>

#include <array>
#include <cmath>

#include "firmware_protocol/console_can.hpp"
#include "hil/fault_injector.hpp"
#include "hil/io/mem_bus.hpp"
#include "hil/io/modbus_server.hpp"
#include "hil/io/wire_fault.hpp"
#include "hil/panel_mapper.hpp"
#include "hil/source_input.hpp"
#include "msgs/clock.hpp"
#include "msgs/failsafe.hpp"
#include "panels/panel_definition.hpp"

namespace fp = rise::firmware_protocol;
using rise::hil::InputFault;
using rise::hil::InputFaultKind;
using rise::hil::PanelMapper;
using rise::hil::PanelSnapshot;

namespace {

rise::panels::PanelDefinition console() {
  return rise::panels::load_panel_definition(std::string(RISE_SOURCE_DIR) + "/panels/definitions/rise_console.yaml");
}

// The console's firmware: one cycle of frames at time t, to a sink.
struct Firmware {
  fp::Encoder encoder{0};
  std::array<int16_t, 6> axes{};
  uint32_t buttons = 1;  // dead-man held
  std::array<uint8_t, 6> switches{0, 2, 0, 0, 0, 0};

  template <class Sink>
  void cycle(int64_t t, Sink&& sink) {
    const auto feed = [&](const fp::Message& m) { sink(encoder.next(m)); };
    feed(fp::HeartbeatFrame{fp::kProtocolVersion, fp::PanelStatus::Operational, static_cast<uint32_t>(t / 1000)});
    feed(fp::AxesFrame{0, {axes[0], axes[1], axes[2]}});
    feed(fp::AxesFrame{1, {axes[3], axes[4], axes[5]}});
    feed(fp::ButtonsFrame{buttons});
    fp::SwitchesFrame s;
    s.position = switches;
    feed(s);
  }
  void cycle_into(PanelMapper& m, int64_t t) {
    cycle(t, [&](const fp::WireFrame& w) { m.on_frame(0, w.can_id, w.data, t); });
  }
};

float axis(const PanelMapper& m, const PanelSnapshot& s, const char* name) {
  return s.controls[*m.definition().find_control(name)].axis;
}

InputFault input_fault(const PanelMapper& m, const char* id, InputFaultKind kind, const char* control, double value,
                       double rate, int64_t start_us, int64_t end_us) {
  InputFault f;
  f.id = id;
  f.kind = kind;
  f.control = *m.definition().find_control(control);
  f.value = value;
  f.rate = rate;
  f.seed = 5;
  f.start_us = start_us;
  f.end_us = end_us;
  return f;
}

constexpr int64_t kT0 = 1'000'000;
constexpr int64_t kCycle = 10'000;

// A mapper with the console healthy for 100 ms, sticks centred, dead-man held.
struct Panel {
  PanelMapper mapper{console()};
  Firmware fw;
  int64_t t = kT0;
  Panel() {
    mapper.on_connection(0, true, t);
    run(10);
  }
  PanelSnapshot run(int cycles) {
    PanelSnapshot s;
    for (int i = 0; i < cycles; ++i) {
      t += kCycle;
      fw.cycle_into(mapper, t);
      s = mapper.evaluate(t);
    }
    return s;
  }
};

}  // namespace

TEST_CASE("a stuck-at fault holds an axis while the stick moves and clears on time", "[hil]") {
  Panel p;
  REQUIRE_FALSE(p.run(1).failsafe);
  REQUIRE(p.mapper.inject_input_fault(input_fault(p.mapper, "stuck", InputFaultKind::StuckAt, "drive_y", 0.6, 0,
                                                  p.t, p.t + 500'000)).empty());
  p.fw.axes[1] = fp::axis_from_unit(-0.9f);
  PanelSnapshot s = p.run(30);
  const float held = axis(p.mapper, s, "drive_y");
  CHECK(held > 0.3f);  // 0.6 through deadband and expo: still clearly forward, not the stick's -0.9
  REQUIRE(s.active_faults.size() == 1);
  CHECK(s.active_faults[0] == "stuck: stuck_at drive_y");
  CHECK_FALSE(s.failsafe);
  s = p.run(30);  // past the 0.5 s duration
  CHECK(axis(p.mapper, s, "drive_y") < -0.5f);
  CHECK(s.active_faults.empty());
}

TEST_CASE("disconnect and out-of-range faults put the control at its safe value and the panel in failsafe",
          "[hil]") {
  Panel p;
  p.fw.axes[1] = fp::axis_from_unit(0.8f);
  p.run(20);
  SECTION("disconnect") {
    REQUIRE(p.mapper.inject_input_fault(input_fault(p.mapper, "cut", InputFaultKind::Disconnect, "drive_y", 0, 0, p.t, 0)).empty());
    const PanelSnapshot s = p.run(1);
    CHECK(s.failsafe);
    CHECK_THAT(s.failsafe_reason, Catch::Contains("drive_y: disconnected (fault)"));
    CHECK(axis(p.mapper, s, "drive_y") == 0.0f);
    CHECK(p.mapper.clear_input_faults("cut", p.t) == 1);
    CHECK_FALSE(p.run(1).failsafe);
  }
  SECTION("out of range") {
    REQUIRE(p.mapper.inject_input_fault(input_fault(p.mapper, "oor", InputFaultKind::OutOfRange, "drive_y", 0, 0, p.t, 0)).empty());
    const PanelSnapshot s = p.run(1);
    CHECK(s.failsafe);
    CHECK_THAT(s.failsafe_reason, Catch::Contains("drive_y: out of range (fault)"));
  }
  SECTION("a dead-man disconnect stops motion") {
    REQUIRE(p.mapper.inject_input_fault(input_fault(p.mapper, "dm", InputFaultKind::Disconnect, "deadman", 0, 0, p.t, 0)).empty());
    const PanelSnapshot s = p.run(1);
    CHECK(s.failsafe);
    CHECK_FALSE(s.deadman);
  }
  SECTION("a kind the control cannot take is refused") {
    CHECK_THAT(p.mapper.inject_input_fault(input_fault(p.mapper, "n", InputFaultKind::Drift, "deadman", 0, 1, p.t, 0)),
               Catch::Contains("not an axis"));
  }
}

TEST_CASE("offset, drift, noise and intermittent faults change an axis as specified, noise by its seed", "[hil]") {
  Panel p;
  p.fw.axes[1] = fp::axis_from_unit(0.0f);
  const std::size_t y = *p.mapper.definition().find_control("drive_y");
  SECTION("offset and drift") {
    float unit = 0.2f;
    std::vector<InputFault> faults{input_fault(p.mapper, "o", InputFaultKind::Offset, "drive_y", 0.3, 0, 0, 0)};
    CHECK(rise::hil::apply_axis_faults(faults, y, 1000, unit) == rise::hil::FaultEffect::Changed);
    CHECK(unit == Approx(0.5f).margin(1e-6));
    faults = {input_fault(p.mapper, "d", InputFaultKind::Drift, "drive_y", 0, 0.25, 0, 0)};
    unit = 0.0f;
    rise::hil::apply_axis_faults(faults, y, 2'000'000, unit);
    CHECK(unit == Approx(0.5f).margin(1e-6));
    unit = 0.0f;
    rise::hil::apply_axis_faults(faults, y, 8'000'000, unit);
    CHECK(unit == 1.0f);  // clamped at full deflection
  }
  SECTION("noise") {
    std::vector<InputFault> a{input_fault(p.mapper, "n", InputFaultKind::Noise, "drive_y", 0.1, 0, 0, 0)};
    auto b = a;
    b[0].seed = 6;
    double sum2 = 0.0;
    int differ = 0;
    for (int64_t t = 0; t < 1000 * 1000; t += 1000) {
      float ua = 0.0f, ua2 = 0.0f, ub = 0.0f;
      rise::hil::apply_axis_faults(a, y, t, ua);
      rise::hil::apply_axis_faults(a, y, t, ua2);
      rise::hil::apply_axis_faults(b, y, t, ub);
      REQUIRE(ua == ua2);
      differ += ua != ub;
      sum2 += static_cast<double>(ua) * ua;
    }
    CHECK(std::sqrt(sum2 / 1000.0) == Approx(0.1).epsilon(0.15));
    CHECK(differ > 900);
  }
  SECTION("intermittent") {
    REQUIRE(p.mapper.inject_input_fault(input_fault(p.mapper, "i", InputFaultKind::Intermittent, "drive_y", 0.5, 0.05, p.t, 0)).empty());
    int lost = 0, ok = 0;
    for (int i = 0; i < 200; ++i) (p.run(1).failsafe ? lost : ok)++;
    CHECK(lost > 40);
    CHECK(ok > 40);
  }
}

TEST_CASE("CAN drop on the wire raises the bad-frame count, and dropping all trips the failsafe at the timeout",
          "[hil]") {
  const std::string url = "mem://fault-drop";
  auto console_side = rise::hil::io::open_can_bus(url);
  rise::hil::io::FaultyCanBus bus(rise::hil::io::open_can_bus(url));
  PanelMapper mapper(console());
  Firmware fw;
  int64_t t = kT0;
  mapper.on_connection(0, true, t);
  const auto cycle = [&] {
    t += kCycle;
    fw.cycle(t, [&](const fp::WireFrame& w) {
      rise::hil::io::CanFrame f;
      f.id = w.can_id;
      f.len = static_cast<uint8_t>(w.data.size());
      std::copy(w.data.begin(), w.data.end(), f.data.begin());
      REQUIRE(console_side->send(f) == rise::hil::io::IoStatus::Ok);
    });
    rise::hil::io::CanFrame f;
    while (bus.receive(f, 0) == rise::hil::io::IoStatus::Ok) rise::hil::apply_can_frame(mapper, 0, f, t);
    return mapper.evaluate(t);
  };
  for (int i = 0; i < 10; ++i) cycle();
  REQUIRE_FALSE(mapper.evaluate(t).failsafe);
  REQUIRE(mapper.evaluate(t).sources[0].frames_bad() == 0);

  SECTION("half the frames lost: skipped alive counters are counted") {
    bus.inject({"drop", rise::hil::io::WireFaultKind::CanDrop, 0.5, 0, 3, 0, 0});
    for (int i = 0; i < 100; ++i) cycle();
    CHECK(bus.dropped() > 150);
    CHECK(mapper.evaluate(t).sources[0].frames_bad() > 0);
    REQUIRE(bus.active(rise::msgs::monotonic_us()).size() == 1);
    CHECK(bus.clear("drop", rise::msgs::monotonic_us()) == 1);
  }
  SECTION("every frame lost: failsafe once the source timeout has passed, healthy after the clear") {
    const int64_t last_good = t;
    bus.inject({"drop", rise::hil::io::WireFaultKind::CanDrop, 1.0, 0, 3, 0, 0});
    const int64_t timeout_us = mapper.definition().sources[0].timeout_ms * 1000;
    while (t + kCycle < last_good + timeout_us) CHECK_FALSE(cycle().failsafe);
    t = last_good + timeout_us;
    const PanelSnapshot late = cycle();
    CHECK(late.failsafe);
    CHECK(rise::msgs::has(late.failsafe_causes, rise::msgs::FailsafeCause::SourceStale));
    bus.clear("", rise::msgs::monotonic_us());
    for (int i = 0; i < 10; ++i) cycle();
    CHECK_FALSE(mapper.evaluate(t).failsafe);
  }
  SECTION("corrupted frames fail their CRC") {
    bus.inject({"c", rise::hil::io::WireFaultKind::CanCorrupt, 1.0, 0, 3, 0, 0});
    const PanelSnapshot s = cycle();
    CHECK(bus.corrupted() == 5);
    CHECK(s.sources[0].errors[static_cast<std::size_t>(fp::DecodeError::BadCrc)] == 5);
    CHECK(s.failsafe);
  }
  SECTION("bus-off: the controller's error frame, then a restart when it ends") {
    bus.inject({"off", rise::hil::io::WireFaultKind::CanBusOff, 0, 0, 3, 0, 0});
    PanelSnapshot s = cycle();
    CHECK(s.sources[0].bus_state == rise::hil::io::CanBusState::BusOff);
    CHECK(s.sources[0].bus_offs == 1);
    CHECK(s.failsafe);
    bus.clear("off", rise::msgs::monotonic_us());
    for (int i = 0; i < 10; ++i) s = cycle();
    CHECK(s.sources[0].bus_state == rise::hil::io::CanBusState::Active);
    CHECK_FALSE(s.failsafe);
  }
  SECTION("delay holds frames back, in order") {
    bus.inject({"late", rise::hil::io::WireFaultKind::CanDelay, 0, 200, 3, 0, 0});
    rise::hil::io::CanFrame f;
    f.id = 0x123;
    f.len = 1;
    f.data[0] = 1;
    console_side->send(f);
    f.data[0] = 2;
    console_side->send(f);
    rise::hil::io::CanFrame got;
    CHECK(bus.receive(got, 0) == rise::hil::io::IoStatus::Timeout);
    REQUIRE(bus.receive(got, 2000) == rise::hil::io::IoStatus::Ok);
    CHECK(got.data[0] == 1);
    REQUIRE(bus.receive(got, 2000) == rise::hil::io::IoStatus::Ok);
    CHECK(got.data[0] == 2);
  }
}

TEST_CASE("Modbus exception and timeout faults answer in place of the slave and are counted", "[hil]") {
  rise::hil::io::ModbusServer server("modbus+tcp-listen://127.0.0.1:0?unit=1", {});
  REQUIRE(server.port() != 0);
  rise::hil::io::FaultyModbusLink link(
      rise::hil::io::open_modbus_link("modbus+tcp://127.0.0.1:" + std::to_string(server.port()) + "?unit=1&timeout_ms=200"));
  REQUIRE(link.is_open());
  std::array<uint16_t, 4> regs{};
  REQUIRE(link.read_input_registers(0, regs).ok());
  link.inject({"ex", rise::hil::io::WireFaultKind::ModbusException, 1.0, 0, 1, 0, 0});
  const auto r = link.read_input_registers(0, regs);
  CHECK(r.status == rise::hil::io::ModbusStatus::Exception);
  CHECK(r.exception_code == 4);
  link.clear("", rise::msgs::monotonic_us());
  link.inject({"to", rise::hil::io::WireFaultKind::ModbusTimeout, 1.0, 0, 1, 0, 0});
  CHECK(link.read_input_registers(0, regs).status == rise::hil::io::ModbusStatus::Timeout);
  CHECK(link.counters().exceptions == 1);
  CHECK(link.counters().timeouts == 1);
  link.clear("to", rise::msgs::monotonic_us());
  CHECK(link.read_input_registers(0, regs).ok());
}

TEST_CASE("the fault injector sends each kind to its layer and refuses what is not the daemon's", "[hil]") {
  PanelMapper probe(console());
  std::vector<std::unique_ptr<rise::hil::io::CanBus>> buses;
  auto faulty = std::make_unique<rise::hil::io::FaultyCanBus>(rise::hil::io::open_can_bus("mem://fault-injector"));
  rise::hil::io::FaultyCanBus* wire = faulty.get();
  buses.push_back(std::move(faulty));
  rise::hil::Bridge bridge(console(), std::move(buses), [](const PanelSnapshot&) {});
  rise::hil::TransportFaults transport;
  rise::hil::FaultInjector injector(bridge, {wire}, &transport);
  const int64_t now = rise::msgs::monotonic_us();
  CHECK(injector.inject({"s", "stuck_at", "drive_y", 0.5, 0, 1.0, 1}, now).empty());
  CHECK(injector.inject({"d", "can_drop", "console", 0.5, 0, 0, 1}, now).empty());
  CHECK(injector.inject({"l", "lcm_loss", "panel_state", 1.0, 0, 0, 1}, now).empty());
  CHECK_THAT(injector.inject({"m", "motor_failure", "left", 0, 0, 0, 1}, now), Catch::Contains("sim fault"));
  CHECK_THAT(injector.inject({"x", "melt", "drive_y", 0, 0, 0, 1}, now), Catch::Contains("unknown fault kind"));
  CHECK_THAT(injector.inject({"y", "stuck_at", "warp", 0, 0, 0, 1}, now), Catch::Contains("no control 'warp'"));
  CHECK_THAT(injector.inject({"z", "modbus_timeout", "console", 0, 0, 0, 1}, now), Catch::Contains("does not apply"));
  const auto active = injector.active(now);
  CHECK(active == std::vector<std::string>{"d: can_drop console", "l: lcm_loss panel_state"});
  CHECK(bridge.snapshot().active_faults == std::vector<std::string>{"s: stuck_at drive_y"});
  rise_msgs::PanelState m{};
  CHECK(transport.pass(m, now).empty());  // lost
  CHECK(transport.lost() == 1);
  CHECK(injector.clear("", now) == 3);
  CHECK(transport.pass(m, now).size() == 1);
}

TEST_CASE("lcm latency holds PanelStates back and releases them in order", "[hil]") {
  rise::hil::TransportFaults transport;
  transport.inject({"lat", false, 0, 100, 1, 0, 0});
  rise_msgs::PanelState a{}, b{};
  a.seq = 1;
  b.seq = 2;
  CHECK(transport.pass(a, 1'000'000).empty());
  CHECK(transport.pass(b, 1'050'000).empty());
  const auto first = transport.pass(rise_msgs::PanelState{}, 1'100'000);
  REQUIRE(first.size() == 1);
  CHECK(first[0].seq == 1);
  const auto second = transport.due(1'150'000);
  REQUIRE(second.size() == 1);
  CHECK(second[0].seq == 2);
}
