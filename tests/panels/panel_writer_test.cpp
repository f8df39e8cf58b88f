// The controls writer (the Console Builder saves through it): load → write →
// load gives the same definition, for every shipped panel definition, keeps
// every comment line, and writes a name that needs quoting so that it loads.

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "firmware_protocol/dbc.hpp"
#include "panels/panel_definition.hpp"
#include "panels/panel_writer.hpp"

using namespace rise::panels;
namespace fs = std::filesystem;

namespace {

const fs::path kDefinitions = fs::path(RISE_SOURCE_DIR) / "panels" / "definitions";

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string point_text(const std::optional<ModbusPoint>& p) { return p ? to_string(*p) : ""; }

// What a control means: everything the mapper reads, not the line it is on.
void check_same_control(const ControlDefinition& a, const ControlDefinition& b) {
  INFO("control " << a.name);
  CHECK(a.name == b.name);
  CHECK(a.kind == b.kind);
  CHECK(a.role == b.role);
  CHECK(a.source == b.source);
  CHECK(to_string(a.signal) == to_string(b.signal));
  CHECK(a.motion == b.motion);
  CHECK(a.deadband == b.deadband);
  CHECK(a.invert == b.invert);
  CHECK(a.scale == b.scale);
  CHECK(a.expo == b.expo);
  CHECK(a.lowpass_ms == b.lowpass_ms);
  CHECK(a.behaviour == b.behaviour);
  CHECK(a.debounce_ms == b.debounce_ms);
  CHECK(a.long_press_ms == b.long_press_ms);
  CHECK(a.pulse_ms == b.pulse_ms);
  CHECK(a.bits == b.bits);
  CHECK(a.encoding == b.encoding);
  CHECK(a.safe_axis == b.safe_axis);
  CHECK(a.safe_button == b.safe_button);
  CHECK(a.safe_switch == b.safe_switch);
  CHECK(a.positions == b.positions);
  CHECK((a.dbc_signal ? a.dbc_message->name + "." + a.dbc_signal->name : "") ==
        (b.dbc_signal ? b.dbc_message->name + "." + b.dbc_signal->name : ""));
  CHECK(a.range_min == b.range_min);
  CHECK(a.range_max == b.range_max);
  CHECK(a.hid_signal == b.hid_signal);
  CHECK(point_text(a.modbus_point) == point_text(b.modbus_point));
  CHECK(a.modbus_type == b.modbus_type);
}

void check_same_definition(const PanelDefinition& a, const PanelDefinition& b) {
  CHECK(a.name == b.name);
  CHECK(a.publish_hz == b.publish_hz);
  REQUIRE(a.sources.size() == b.sources.size());
  for (std::size_t i = 0; i < a.sources.size(); ++i) {
    CHECK(a.sources[i].name == b.sources[i].name);
    CHECK(a.sources[i].protocol == b.sources[i].protocol);
    CHECK(a.sources[i].timeout_ms == b.sources[i].timeout_ms);
  }
  REQUIRE(a.controls.size() == b.controls.size());
  for (std::size_t i = 0; i < a.controls.size(); ++i) check_same_control(a.controls[i], b.controls[i]);
  CHECK(a.leds.size() == b.leds.size());
  CHECK(a.displays.size() == b.displays.size());
  CHECK(a.rumbles.size() == b.rumbles.size());
  CHECK(a.buzzer_source == b.buzzer_source);
}

}  // namespace

TEST_CASE("load, write, load keeps every shipped panel definition's meaning and comments", "[panel_writer]") {
  int files = 0;
  for (const auto& entry : fs::directory_iterator(kDefinitions)) {
    if (entry.path().extension() != ".yaml") continue;
    ++files;
    const std::string path = entry.path().string();
    INFO(path);
    const std::string text = read_text(entry.path());
    const PanelDefinition original = load_panel_definition(path);
    const auto controls = read_panel_controls(text, path);
    REQUIRE(controls.size() == original.controls.size());
    std::vector<int> lines;
    const std::string written = write_panel_controls(text, controls, &lines);
    INFO(written);
    const PanelDefinition again = parse_panel_definition(written, path);
    check_same_definition(original, again);
    // Each control's line is where the loader found it.
    REQUIRE(lines.size() == again.controls.size());
    for (std::size_t i = 0; i < lines.size(); ++i) CHECK(lines[i] == again.controls[i].line);
    // Every comment line survives (the controls' comments stand above them).
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line))
      if (const auto hash = line.find("# "); hash != std::string::npos && line.find_first_not_of(' ') == hash)
        CHECK(written.find(line.substr(hash)) != std::string::npos);
    // Writing is stable: a second round gives the same text.
    CHECK(write_panel_controls(written, read_panel_controls(written, path)) == written);
  }
  CHECK(files >= 6);
}

TEST_CASE("a new control with a comment and a name that needs quoting loads as written", "[panel_writer]") {
  const std::string path = (kDefinitions / "rise_console.yaml").string();
  const std::string text = read_text(path);
  auto controls = read_panel_controls(text, path);
  ControlEntry horn;
  horn.comment = "learned: button.7 of console\nthe horn: a second line";
  horn.fields = {{"name", {false, "horn: loud", {}}},
                 {"kind", {false, "button", {}}},
                 {"signal", {false, "button.7", {}}},
                 {"safe", {false, "false", {}}}};
  controls.push_back(horn);
  const std::string written = write_panel_controls(text, controls);
  INFO(written);
  CHECK(written.find("  # learned: button.7 of console\n  # the horn: a second line\n") != std::string::npos);
  const PanelDefinition def = parse_panel_definition(written, path);
  REQUIRE(def.find_control("horn: loud"));
  const auto& c = def.controls[*def.find_control("horn: loud")];
  CHECK(c.kind == ControlKind::Button);
  CHECK(to_string(c.signal) == "button.7");
  // The feedback section after the controls is still there.
  CHECK(def.leds.size() == 3);
}

TEST_CASE("a text without controls gets them appended; a malformed one names its line", "[panel_writer]") {
  ControlEntry c;
  c.fields = {{"name", {false, "x", {}}}, {"positions", {true, "", {{false, "a", {}}, {false, "b", {}}}}}};
  const std::string written = write_panel_controls("panel: p\n", {c});
  CHECK(written == "panel: p\n\ncontrols:\n  - {name: x, positions: [a, b]}\n");
  // A comment cannot end itself: a carriage return in it is no line break.
  c.comment = "x\rcontrols: 3";
  const std::string commented = write_panel_controls("panel: p\n", {c});
  CHECK(commented.find("  # x controls: 3\n") != std::string::npos);
  CHECK(read_panel_controls(commented, "f.yaml").size() == 1);
  CHECK_THROWS_WITH(read_panel_controls("panel: p\ncontrols: 3\n", "f.yaml"),
                    Catch::Contains("f.yaml:2: controls: expected a list"));
  CHECK_THROWS_WITH(read_panel_controls("panel: p\ncontrols:\n  - [1, 2]\n", "f.yaml"),
                    Catch::Contains("f.yaml:3: controls[0]: expected a mapping"));
}
