// PanelMapper's protocol-neutral entry points (on_inputs, on_source_error)
// as the bridge's Modbus source uses them, with explicit times (µs), and the
// rise-modbus-v1 source settings of a panel definition.

#include <catch2/catch.hpp>

#include <fstream>
#include <sstream>

#include "hil/panel_mapper.hpp"
#include "msgs/failsafe.hpp"
#include "panels/panel_definition.hpp"

namespace fp = rise::firmware_protocol;
using rise::hil::PanelMapper;
using E = rise::hil::PanelMapper::SourceError;

namespace {

std::string console_yaml() {
  std::ifstream in(std::string(RISE_SOURCE_DIR) + "/panels/definitions/rise_console.yaml");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The reference console with its source line `node: 0` replaced by `source_keys`.
rise::panels::PanelDefinition with_source(const std::string& protocol, const std::string& source_keys) {
  std::string yaml = console_yaml();
  const std::string from = "protocol: rise-can-v1\n    node: 0";
  yaml.replace(yaml.find(from), from.size(), "protocol: " + protocol + "\n    " + source_keys);
  return rise::panels::parse_panel_definition(yaml, "modbus.yaml");
}

fp::ConsoleInputs operational(uint16_t counter) {
  fp::ConsoleInputs in;
  in.status = fp::PanelStatus::Operational;
  in.buttons = 1u;                     // dead-man held
  in.switches = {0, 2, 0, 0, 0, 0};    // mode=drive, speed=fast
  in.axes[1] = fp::axis_from_unit(0.5f);
  in.alive_counter = counter;
  return in;
}

}  // namespace

TEST_CASE("a panel definition accepts rise-modbus-v1 sources with poll_hz and unit", "[hil]") {
  SECTION("good") {
    const auto def = with_source("rise-modbus-v1", "unit: 7\n    poll_hz: 200");
    CHECK(def.sources[0].is_modbus());
    CHECK(def.sources[0].unit == 7);
    CHECK(def.sources[0].poll_hz == Approx(200.0).margin(1e-9));
    const auto defaults = with_source("rise-modbus-v1", "timeout_ms: 100");
    CHECK(defaults.sources[0].unit == 1);
    CHECK(defaults.sources[0].poll_hz == Approx(50.0).margin(1e-9));
  }
  SECTION("bad") {
    const auto [protocol, keys, message] = GENERATE(table<std::string, std::string, std::string>({
        {"rise-modbus-v1", "unit: 0", "sources[0].unit: must be 1..247"},
        {"rise-modbus-v1", "poll_hz: 0.5", "sources[0].poll_hz: must be 1..1000"},
        {"rise-can-v1", "poll_hz: 50", "sources[0].poll_hz: only for protocols rise-modbus-v1 and modbus"},
        {"rise-can-v2", "node: 0", "unknown protocol 'rise-can-v2' (known: rise-can-v1, rise-modbus-v1, modbus, dbc, j1939, hid"},
    }));
    try {
      with_source(protocol, keys);
      FAIL("no exception");
    } catch (const std::runtime_error& e) {
      CHECK_THAT(e.what(), Catch::Contains(message) && Catch::Contains("modbus.yaml:"));
    }
  }
}

TEST_CASE("the mapper takes whole input blocks and fails a Modbus source on a bad CRC or a frozen counter",
          "[hil]") {
  const auto def = with_source("rise-modbus-v1", "timeout_ms: 100");
  const auto drive_y = *def.find_control("drive_y");
  PanelMapper mapper(def);
  mapper.on_connection(0, true, 1000);
  CHECK(mapper.on_inputs(0, operational(1), 1000));
  CHECK_FALSE(mapper.on_inputs(0, operational(2), 11000));  // same values: no change
  auto snap = mapper.evaluate(12000);
  REQUIRE_FALSE(snap.failsafe);
  CHECK(snap.controls[drive_y].axis == Approx((0.5 - 0.05) / 0.95).margin(1e-3));
  CHECK(snap.sources[0].frames_ok == 2);

  SECTION("a block with a bad CRC fails the check until recovery_frames good blocks") {
    mapper.on_source_error(0, E::BadCrc, 21000);
    snap = mapper.evaluate(21000);
    CHECK(snap.failsafe);
    CHECK(rise::msgs::has(snap.failsafe_causes, rise::msgs::FailsafeCause::ProtectionFailed));
    CHECK(snap.sources[0].errors[static_cast<std::size_t>(fp::DecodeError::BadCrc)] == 1);
    for (uint16_t i = 0; i < def.sources[0].recovery_frames; ++i) mapper.on_inputs(0, operational(3 + i), 31000 + i);
    CHECK_FALSE(mapper.evaluate(40000).failsafe);
  }
  SECTION("stale counters are counted, not failed, until the timeout passes") {
    mapper.on_source_error(0, E::StaleCounter, 21000);
    CHECK_FALSE(mapper.evaluate(21000).failsafe);
    snap = mapper.evaluate(11000 + 100000 + 1);
    CHECK(snap.failsafe);
    CHECK(rise::msgs::has(snap.failsafe_causes, rise::msgs::FailsafeCause::SourceStale));
    CHECK(snap.controls[drive_y].axis == 0.0f);
    CHECK(snap.sources[0].errors[static_cast<std::size_t>(fp::DecodeError::RepeatedCounter)] == 1);
  }
  SECTION("transport errors are counted by kind") {
    mapper.on_source_error(0, E::Timeout, 21000);
    mapper.on_source_error(0, E::Timeout, 22000);
    mapper.on_source_error(0, E::Exception, 23000);
    snap = mapper.evaluate(24000);
    CHECK_FALSE(snap.failsafe);
    CHECK(snap.sources[0].timeouts == 2);
    CHECK(snap.sources[0].exceptions == 1);
  }
  SECTION("a console reporting a fault puts the panel in failsafe") {
    auto in = operational(3);
    in.status = fp::PanelStatus::Fault;
    CHECK(mapper.on_inputs(0, in, 21000));
    CHECK(mapper.evaluate(21000).failsafe_reason.find("console status Fault") != std::string::npos);
  }
}
