#include <catch2/catch.hpp>

#include <string>

#include "panels/panel_definition.hpp"
#include "panels/timeline.hpp"

using namespace rise::panels;

namespace {
const std::string kShipped = std::string(RISE_SOURCE_DIR) + "/panels/definitions/rise_console.yaml";

const char* kGood = R"(panel: test-panel
sources:
  - {name: console, protocol: rise-can-v1, node: 2}
controls:
  - {name: drive_y, kind: axis, signal: axis.1, deadband: 0.1, invert: true, motion: true, safe: 0.0}
  - {name: deadman, kind: button, signal: button.0, role: deadman, safe: false}
  - {name: mode, kind: switch, signal: switch.0, positions: [drive, arm], safe: arm}
)";

std::string error_of(const std::string& text) {
  try {
    parse_panel_definition(text, "broken.yaml");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}
}  // namespace

TEST_CASE("the shipped rise-console definition loads with every control of the reference console",
          "[panels]") {
  const PanelDefinition def = load_panel_definition(kShipped);
  CHECK(def.name == "rise-console");
  CHECK(def.publish_hz == Approx(100.0));
  REQUIRE(def.sources.size() == 1);
  CHECK(def.sources[0].node == 0);
  for (const char* name : {"drive_x", "drive_y", "arm_x", "arm_y", "arm_twist", "deadman", "estop",
                           "gripper_open", "gripper_close", "mode", "speed"})
    CHECK(def.find_control(name).has_value());
  const auto& speed = def.controls[*def.find_control("speed")];
  CHECK(speed.positions == std::vector<std::string>{"slow", "medium", "fast"});
  CHECK(speed.safe_switch == 0);
  CHECK(def.controls[*def.find_control("estop")].safe_button == true);
  CHECK(def.controls[*def.find_control("deadman")].role == ControlRole::Deadman);
  CHECK(def.leds.size() == 3);
  REQUIRE(def.displays.size() == 1);
  CHECK(def.displays[0].name == "speed");
  CHECK(def.buzzer_source.has_value());
}

TEST_CASE("a good definition is read field by field", "[panels]") {
  const PanelDefinition def = parse_panel_definition(kGood, "good.yaml");
  REQUIRE(def.controls.size() == 3);
  const auto& y = def.controls[0];
  CHECK(y.kind == ControlKind::Axis);
  CHECK(y.signal.kind == SignalRef::Kind::Axis);
  CHECK(y.signal.index == 1);
  CHECK(y.deadband == Approx(0.1f).margin(1e-6));
  CHECK(y.invert);
  CHECK(y.motion);
  CHECK(y.line == 5);
  CHECK(def.controls[2].safe_switch == 1);
  CHECK(def.sources[0].node == 2);
  CHECK(def.sources[0].timeout_ms == 50);
}

TEST_CASE("a wrong definition is refused with file:line and the key", "[panels]") {
  struct Case {
    const char* find;
    const char* replace;
    const char* expected;
  };
  const auto c = GENERATE(
      Case{"signal: axis.1", "signal: JOY_Y", "broken.yaml:5: controls.drive_y.signal: unknown signal 'JOY_Y'"},
      Case{"signal: axis.1", "signal: button.1", "broken.yaml:5: controls.drive_y.signal: signal 'button.1' does not fit"},
      Case{"deadband: 0.1", "deadbnd: 0.1", "broken.yaml:5: controls[0].deadbnd: unknown key"},
      // A list as a key (yaml-cpp's own bad conversion escaped here; found by tests/fuzz/configs_fuzz.cpp).
      Case{"deadband: 0.1", "[deadband]: 0.1", "broken.yaml:5: controls[0]: a key must be a name, not a list or mapping"},
      Case{"node: 2", "node: 16", "broken.yaml:3: sources[0].node: must be 0..15"},
      Case{"protocol: rise-can-v1", "protocol: flexray", "broken.yaml:3: sources[0].protocol: unknown protocol 'flexray'"},
      Case{"protocol: rise-can-v1", "protocol: j1939", "broken.yaml:3: sources[0].dbc: missing"},
      Case{"safe: arm", "safe: park", "broken.yaml:7: controls.mode.safe: 'park' is not one of the positions"},
      Case{", safe: 0.0}", "}", "broken.yaml:5: controls.drive_y.safe: missing"},
      Case{"deadband: 0.1", "deadband: lots", "broken.yaml:5: controls.drive_y.deadband: cannot read 'lots' as a number"},
      Case{"signal: button.0", "signal: axis.1", "broken.yaml:6: controls.deadman.signal: signal 'axis.1' does not fit"},
      Case{"role: deadman", "role: boss", "broken.yaml:6: controls.deadman.role: unknown role 'boss'"},
      Case{"name: mode", "name: drive_y", "broken.yaml:7: controls.drive_y.name: duplicate control name"});
  std::string text = kGood;
  const auto at = text.find(c.find);
  REQUIRE(at != std::string::npos);
  text.replace(at, std::string(c.find).size(), c.replace);
  const std::string error = error_of(text);
  INFO(error);
  // Every message starts with file:line and names the key.
  CHECK(error.rfind(c.expected, 0) == 0);
}

TEST_CASE("a definition with motion controls but no dead-man is refused", "[panels]") {
  std::string text = kGood;
  text.replace(text.find("role: deadman, "), std::string("role: deadman, ").size(), "");
  const auto error = error_of(text);
  CHECK(error.find("broken.yaml:") == 0);
  CHECK(error.find("role: deadman") != std::string::npos);
}

TEST_CASE("YAML syntax errors name the line", "[panels]") {
  const auto error = error_of("panel: x\nsources: [\n  {name: a\n");
  CHECK(error.rfind("broken.yaml:", 0) == 0);
  CHECK(error.find("no error") == std::string::npos);
}

TEST_CASE("a missing definition file is reported with its path and the OS's reason", "[panels]") {
  CHECK_THROWS_WITH(load_panel_definition("/nonexistent/panel.yaml"),
                    "/nonexistent/panel.yaml: cannot open: No such file or directory");
}

TEST_CASE("signals are parsed within the protocol's range", "[panels]") {
  CHECK(parse_signal("axis.5").has_value());
  CHECK_FALSE(parse_signal("axis.6").has_value());
  CHECK(parse_signal("button.31").has_value());
  CHECK_FALSE(parse_signal("button.32").has_value());
  CHECK_FALSE(parse_signal("switch.").has_value());
  CHECK_FALSE(parse_signal("axis.-1").has_value());
  CHECK(to_string(*parse_signal("switch.3")) == "switch.3");
}

TEST_CASE("timelines are read against the definition and refuse what it does not know", "[panels]") {
  const PanelDefinition def = parse_panel_definition(kGood, "good.yaml");
  SECTION("good lines") {
    const Timeline t = parse_timeline(
        "# comment\n0.0 mode drive\n0.5 deadman pressed\n1.0 drive_y -0.5  # back\n2 @silent\n"
        "2.5 @corrupt 3\n3 @status fault\n4 @end\n",
        "t.txt", def);
    REQUIRE(t.events.size() == 7);
    CHECK(t.events[0].position == 0);
    CHECK(t.events[1].pressed);
    CHECK(t.events[2].axis == Approx(-0.5f).margin(1e-6));
    CHECK(t.events[3].kind == TimelineEvent::Kind::Silent);
    CHECK(t.events[4].count == 3);
    CHECK(t.events[5].status == 2);
    CHECK(t.end_time_s() == Approx(4.0));
  }
  SECTION("bad lines") {
    CHECK_THROWS_WITH(parse_timeline("0 JOY_Y 0.5\n", "t.txt", def), Catch::StartsWith("t.txt:1: unknown control 'JOY_Y'"));
    CHECK_THROWS_WITH(parse_timeline("0 drive_y 1.5\n", "t.txt", def), Catch::StartsWith("t.txt:1: drive_y: '1.5' is not an axis value"));
    CHECK_THROWS_WITH(parse_timeline("1 mode arm\n0.5 mode drive\n", "t.txt", def), Catch::StartsWith("t.txt:2: time"));
    CHECK_THROWS_WITH(parse_timeline("0 mode park\n", "t.txt", def), Catch::StartsWith("t.txt:1: mode: 'park'"));
    CHECK_THROWS_WITH(parse_timeline("0 @explode\n", "t.txt", def), Catch::StartsWith("t.txt:1: unknown directive"));
    CHECK_THROWS_WITH(parse_timeline("0 deadman maybe\n", "t.txt", def), Catch::StartsWith("t.txt:1: deadman"));
  }
}

TEST_CASE("an evdev hid source: mapping: sdl, sdl.NAME signals, errors with file:line and key", "[panels]") {
  const std::string head =
      "panel: pad\n"
      "sources:\n";
  const std::string controls =
      "controls:\n"
      "  - {name: steer, kind: axis, signal: sdl.leftx, safe: 0}\n";
  CHECK_THAT(error_of(head + "  - {name: pad, protocol: hid, device: 'evdev://045e:028e'}\n" + controls),
             Catch::Contains("broken.yaml:5") && Catch::Contains("sdl.NAME needs mapping: sdl on source 'pad'"));
  CHECK_THAT(error_of(head + "  - {name: pad, protocol: hid, mapping: sdl}\n" + controls),
             Catch::Contains("broken.yaml:3") && Catch::Contains("sdl_db"));
  CHECK_THAT(error_of(head + "  - {name: pad, protocol: hid, mapping: steam, sdl_db: x.txt}\n" + controls),
             Catch::Contains("broken.yaml:3") && Catch::Contains("unknown mapping 'steam' (known: sdl)"));
  CHECK_THAT(error_of(head + "  - {name: pad, protocol: hid, mapping: sdl, sdl_db: /nonexistent/db.txt}\n" + controls),
             Catch::Contains("sources[0].sdl_db") && Catch::Contains("/nonexistent/db.txt: cannot read"));
  CHECK_THAT(error_of(head + "  - {name: pad, protocol: hid, device: 'evdev:/dev/input/event1'}\n" + controls),
             Catch::Contains("sources[0].device") && Catch::Contains("evdev://"));
  CHECK_THAT(error_of(head + "  - {name: pad, protocol: rise-can-v1, mapping: sdl}\n" + controls),
             Catch::Contains("sources[0].mapping") && Catch::Contains("only for protocol hid"));
  const auto def = parse_panel_definition(
      head + "  - {name: pad, protocol: hid, device: 'evdev://045e:028e'}\n"
             "controls:\n  - {name: look, kind: axis, signal: abs_ry, safe: 0}\n",
      "ok.yaml");
  CHECK(def.sources[0].device == "evdev://045e:028e");
  CHECK(def.controls[0].hid_signal == "abs_ry");
}
