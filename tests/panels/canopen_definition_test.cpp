// protocol: canopen in a panel definition: the EDS beside it, controls and
// feedback bound to PDO-mapped objects by name or index:subindex, and every
// mistake named by file:line and key.

#include <catch2/catch.hpp>

#include <string>

#include "firmware_protocol/canopen_eds.hpp"
#include "firmware_protocol/dbc.hpp"
#include "panels/panel_definition.hpp"

namespace {

const std::string kDir = std::string(RISE_SOURCE_DIR) + "/panels/definitions";

// A one-source canopen panel; `source_extra` goes into the source's map,
// `controls` and `feedback` are YAML lines.
std::string panel(const std::string& source_extra, const std::string& controls, const std::string& feedback = "") {
  return "panel: co\n"
         "sources:\n"
         "  - {name: console, protocol: canopen, eds: " + kDir + "/rise_console_canopen.eds" + source_extra + "}\n"
         "controls:\n" + controls + feedback;
}

const std::string kDeadman = "  - {name: deadman, kind: button, signal: Dead-man, role: deadman, safe: false}\n";

std::string error_of(const std::string& text) {
  try {
    rise::panels::parse_panel_definition(text, "co.yaml");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST_CASE("the shipped canopen console binds objects by name and by index:subindex", "[panels][canopen]") {
  const auto def = rise::panels::load_panel_definition(kDir + "/rise_console_canopen.yaml");
  REQUIRE(def.sources.size() == 1);
  const auto& s = def.sources[0];
  CHECK(s.is_canopen());
  CHECK(s.node == 5);
  CHECK(s.timeout_ms == 150);        // 1.5 × the 100 ms heartbeat (0x1017)
  CHECK(s.sync_period_us == 10000);  // 0x1006
  REQUIRE(s.eds);
  const auto& x = def.controls[*def.find_control("drive_x")];  // by name
  const auto& y = def.controls[*def.find_control("drive_y")];  // by 0x2000:02
  CHECK(x.dbc_message->name == "TPDO1");
  CHECK(x.dbc_signal->start_bit == 0);
  CHECK(y.dbc_signal->start_bit == 16);
  CHECK(y.range_min == -32767);
  CHECK(y.range_max == 32767);
  const auto& estop = def.controls[*def.find_control("estop")];
  CHECK(estop.dbc_message->id == 0x285);
  CHECK(estop.dbc_signal->start_bit == 1);
  CHECK(estop.dbc_signal->length_bits == 1);
  const auto& camera = def.controls[*def.find_control("camera")];
  CHECK(camera.dbc_signal->start_bit == 8);
  REQUIRE(def.leds.size() == 4);
  CHECK(def.leds[1].pdo_message->id == 0x205);  // fault by 0x2100:02
  CHECK(def.leds[1].pdo_signal->start_bit == 1);
  REQUIRE(def.displays.size() == 1);
  CHECK(def.displays[0].pdo_signal->start_bit == 8);
  CHECK(def.displays[0].decimals == 2);
}

TEST_CASE("canopen definition mistakes name file:line and the key", "[panels][canopen]") {
  SECTION("an object the EDS does not have") {
    CHECK(error_of(panel(", node: 5", kDeadman + "  - {name: a, kind: axis, signal: Nope, safe: 0}\n")) ==
          "co.yaml:6: controls.a.signal: no object 'Nope' (a ParameterName or index:subindex) in " + kDir +
              "/rise_console_canopen.eds");
    CHECK_THAT(error_of(panel(", node: 5", kDeadman + "  - {name: a, kind: axis, signal: '0x2000:07', safe: 0}\n")),
               Catch::StartsWith("co.yaml:6: controls.a.signal: no object 0x2000:07"));
  }
  SECTION("a control bound to an object only an RPDO maps") {
    CHECK_THAT(error_of(panel(", node: 5", kDeadman + "  - {name: a, kind: button, signal: Fault LED, safe: false}\n")),
               Catch::StartsWith("co.yaml:6: controls.a.signal: 0x2100:02 'Fault LED' is not in a TPDO of") &&
                   Catch::Contains("(an RPDO maps it: the console reads it)"));
  }
  SECTION("an LED bound to an object a TPDO maps") {
    CHECK_THAT(error_of(panel(", node: 5", kDeadman, "feedback:\n  leds:\n    - {name: power, signal: Horn}\n")),
               Catch::StartsWith("co.yaml:8: feedback.leds.power.signal: 0x2001:03 'Horn' is not in a RPDO"));
  }
  SECTION("an LED written twice, an LED by bit, a buzzer") {
    CHECK_THAT(error_of(panel(", node: 5", kDeadman,
                              "feedback:\n  leds:\n    - {name: a, signal: Power LED}\n    - {name: b, signal: "
                              "'0x2100:01'}\n")),
               Catch::StartsWith("co.yaml:9: feedback.leds.b.signal: already written by another LED or display"));
    CHECK_THAT(error_of(panel(", node: 5", kDeadman, "feedback:\n  leds:\n    - {name: a, bit: 0}\n")),
               Catch::StartsWith("co.yaml:8: feedback.leds.a.bit: a canopen source's LED is an RPDO-mapped object"));
    CHECK_THAT(error_of(panel(", node: 5", kDeadman, "feedback:\n  buzzer: {source: console}\n")),
               Catch::Contains("feedback.buzzer.source: a canopen source has no buzzer"));
  }
  SECTION("an axis on an object without limits needs a range") {
    CHECK_THAT(error_of(panel(", node: 5", kDeadman + "  - {name: a, kind: axis, signal: Horn, safe: 0}\n")),
               Catch::StartsWith("co.yaml:6: controls.a.range: needs min < max (the EDS gives no LowLimit/HighLimit "
                                 "for 0x2001:03)"));
    const auto def = rise::panels::parse_panel_definition(
        panel(", node: 5", kDeadman + "  - {name: a, kind: axis, signal: Horn, range: [0, 1], safe: 0}\n"), "co.yaml");
    CHECK(def.controls[1].range_max == 1.0);
  }
  SECTION("the node id") {
    CHECK(error_of(panel("", kDeadman)) == "co.yaml:3: sources[0].node: missing (the CANopen node id, 1..127)");
    CHECK(error_of(panel(", node: 0", kDeadman)) == "co.yaml:3: sources[0].node: a CANopen node id is 1..127");
    CHECK(error_of(panel(", node: 128", kDeadman)) == "co.yaml:3: sources[0].node: a CANopen node id is 1..127");
  }
  SECTION("a heartbeat consumer time not above the producer's, a SYNC period of 0 with a synchronous TPDO") {
    CHECK_THAT(error_of(panel(", node: 5, timeout_ms: 100", kDeadman)),
               Catch::StartsWith("co.yaml:3: sources[0].timeout_ms: the heartbeat consumer time must exceed the "
                                 "node's producer heartbeat time (100 ms"));
    CHECK_THAT(error_of(panel(", node: 5, sync_ms: 0", kDeadman)),
               Catch::StartsWith("co.yaml:3: sources[0].sync_ms: a TPDO of") &&
                   Catch::Contains("is synchronous but no SYNC period is given"));
    const auto def = rise::panels::parse_panel_definition(panel(", node: 5, sync_ms: 20, timeout_ms: 300", kDeadman),
                                                          "co.yaml");
    CHECK(def.sources[0].sync_period_us == 20000);
    CHECK(def.sources[0].timeout_ms == 300);
  }
  SECTION("an EDS error carries the YAML's place and the EDS's") {
    CHECK_THAT(error_of("panel: co\nsources:\n  - {name: c, protocol: canopen, node: 5, eds: /nonexistent.eds}\n"
                        "controls:\n" + kDeadman),
               Catch::StartsWith("co.yaml:3: sources[0].eds: /nonexistent.eds: cannot open"));
  }
  SECTION("canopen keys on another protocol") {
    CHECK_THAT(error_of("panel: p\nsources:\n  - {name: c, protocol: rise-can-v1, eds: x.eds}\ncontrols:\n"
                        "  - {name: d, kind: button, signal: button.0, safe: false}\n"),
               Catch::StartsWith("co.yaml:3: sources[0].eds: only for protocol canopen"));
  }
}
