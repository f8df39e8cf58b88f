// The virtual panel under the daemon's safety rules: what a page sends
// becomes a PanelState with a "virtual" source, and a page that stops sending
// (or says goodbye) leaves the safe state.

#include <catch2/catch.hpp>

#include <algorithm>

#include "instructor/virtual_panel.hpp"
#include "msgs/panel_state_controls.hpp"
#include "panels/panel_definition.hpp"

namespace {
using rise::instructor::VirtualControls;
using rise::instructor::VirtualPanel;

rise::panels::PanelDefinition console() {
  return rise::panels::load_panel_definition(std::string(RISE_SOURCE_DIR) + "/panels/definitions/rise_console.yaml");
}

float axis(const rise_msgs::PanelState& m, const std::string& name) {
  const auto value = rise::msgs::find_axis(m, name);
  if (!value) FAIL("no axis " << name);
  return *value;
}
bool button(const rise_msgs::PanelState& m, const std::string& name) {
  const auto pressed = rise::msgs::find_button(m, name);
  if (!pressed) FAIL("no button " << name);
  return *pressed;
}
std::string label(const rise_msgs::PanelState& m, const std::string& name) {
  const auto position = rise::msgs::find_switch_label(m, name);
  if (!position) FAIL("no switch " << name);
  return *position;
}

VirtualControls driving() {
  VirtualControls c;
  c.axes = {{"drive_y", 1.0f}, {"drive_x", -0.5f}};
  c.buttons = {{"deadman", true}, {"estop", false}};
  c.switches = {{"mode", "drive"}, {"speed", "fast"}};
  return c;
}
}  // namespace

TEST_CASE("a virtual panel publishes what its page sends under a virtual source", "[instructor]") {
  VirtualPanel panel(console(), 200, "127.0.0.1");
  const int64_t t0 = 1'000'000;
  SECTION("before any update the panel is failsafe at its safe values") {
    const auto m = panel.state("v1", t0, 0);
    CHECK(m.failsafe);
    CHECK_FALSE(m.deadman);
    CHECK(axis(m, "drive_y") == 0.0f);
    REQUIRE(m.sources.size() == 1);
    CHECK(m.sources[0].name == "virtual");
    CHECK(m.sources[0].url == "virtual://127.0.0.1");
  }
  SECTION("an update drives: dead-man held, the stick through the console's deadband, the switches by label") {
    REQUIRE_FALSE(panel.update(driving(), t0).has_value());
    const auto m = panel.state("v1", t0 + 10'000, 0);
    CHECK_FALSE(m.failsafe);
    CHECK(m.deadman);
    CHECK(axis(m, "drive_y") == Approx(1.0f).margin(1e-4));
    // deadband 0.05 rescaled: (0.5 - 0.05) / 0.95
    CHECK(axis(m, "drive_x") == Approx(-0.45f / 0.95f).margin(1e-4));
    CHECK(button(m, "deadman"));
    CHECK_FALSE(button(m, "gripper_open"));
    CHECK(label(m, "speed") == "fast");
    CHECK(label(m, "mode") == "drive");
    CHECK(m.sources[0].connected);
    CHECK_FALSE(m.sources[0].stale);
    CHECK(m.trainee_id == "v1");
  }
  SECTION("releasing the dead-man zeroes the motion controls") {
    auto c = driving();
    c.buttons["deadman"] = false;
    REQUIRE_FALSE(panel.update(c, t0).has_value());
    const auto m = panel.state("v1", t0 + 10'000, 0);
    CHECK_FALSE(m.deadman);
    CHECK(axis(m, "drive_y") == 0.0f);
  }
  SECTION("the e-stop makes the panel failsafe") {
    auto c = driving();
    c.buttons["estop"] = true;
    REQUIRE_FALSE(panel.update(c, t0).has_value());
    const auto m = panel.state("v1", t0 + 10'000, 0);
    CHECK(m.failsafe);
    CHECK(axis(m, "drive_y") == 0.0f);
  }
  SECTION("a control the page leaves out keeps its safe value: no e-stop state reads as pressed") {
    auto c = driving();
    c.buttons.erase("estop");
    REQUIRE_FALSE(panel.update(c, t0).has_value());
    const auto m = panel.state("v1", t0 + 10'000, 0);
    CHECK(m.failsafe);
    CHECK(m.failsafe_reason == "e-stop pressed");
  }
  SECTION("a page that stops sending is failsafe once its timeout has passed") {
    REQUIRE_FALSE(panel.update(driving(), t0).has_value());
    CHECK_FALSE(panel.state("v1", t0 + 199'000, 0).failsafe);
    const auto m = panel.state("v1", t0 + 201'000, 0);
    CHECK(m.failsafe);
    CHECK_FALSE(m.deadman);
    CHECK(axis(m, "drive_y") == 0.0f);
    CHECK(m.sources[0].stale);
    CHECK(m.failsafe_reason.find("virtual") != std::string::npos);
    SECTION("and drives again on the next update") {
      REQUIRE_FALSE(panel.update(driving(), t0 + 300'000).has_value());
      CHECK_FALSE(panel.state("v1", t0 + 301'000, 0).failsafe);
    }
  }
  SECTION("a page that says goodbye is failsafe at once") {
    REQUIRE_FALSE(panel.update(driving(), t0).has_value());
    panel.disconnect(t0 + 1'000);
    const auto m = panel.state("v1", t0 + 2'000, 0);
    CHECK(m.failsafe);
    CHECK_FALSE(m.sources[0].connected);
    CHECK(axis(m, "drive_y") == 0.0f);
  }
  SECTION("seq counts up by one per state") {
    const auto a = panel.state("v1", t0, 0), b = panel.state("v1", t0 + 1, 0);
    CHECK(b.seq == a.seq + 1);
  }
}

TEST_CASE("a virtual panel refuses unknown controls and positions and takes nothing then", "[instructor]") {
  VirtualPanel panel(console(), 200, "test");
  const int64_t t0 = 1'000'000;
  REQUIRE_FALSE(panel.update(driving(), t0).has_value());
  auto c = driving();
  SECTION("an unknown axis") {
    c.axes["throttle"] = 1.0f;
    const auto e = panel.update(c, t0 + 100'000);
    REQUIRE(e.has_value());
    CHECK(*e == "axis 'throttle': no such axis in rise-console");
  }
  SECTION("a button name given as an axis") {
    c.axes["deadman"] = 1.0f;
    CHECK(panel.update(c, t0 + 100'000).has_value());
  }
  SECTION("an unknown switch position") {
    c.switches["speed"] = "warp";
    const auto e = panel.update(c, t0 + 100'000);
    REQUIRE(e.has_value());
    CHECK(*e == "switch 'speed': no position 'warp'");
  }
  // The refused update did not refresh the source: it goes stale on time.
  CHECK(panel.state("v", t0 + 250'000, 0).failsafe);
}

TEST_CASE("a virtual panel needs a console definition with one source", "[instructor]") {
  auto d = console();
  d.sources.push_back(d.sources[0]);
  d.sources[1].name = "second";
  CHECK_THROWS_WITH(VirtualPanel(d, 200, "x"), Catch::Contains("needs a definition with one source"));
}

TEST_CASE("a virtual panel takes input faults like rise-hild and clears them", "[instructor]") {
  VirtualPanel panel(console(), 200, "test");
  const int64_t t0 = 1'000'000;
  REQUIRE_FALSE(panel.update(driving(), t0).has_value());
  rise_msgs::FaultCommand c{};
  c.action = "inject";
  c.fault_id = "stuck";
  c.kind = "stuck_at";
  c.target = "drive_y";
  c.value = 0.4;
  c.duration_s = 0.5;
  REQUIRE(panel.apply(c, t0) == "");
  auto m = panel.state("v", t0 + 1'000, 0);
  CHECK(axis(m, "drive_y") == Approx((0.4 - 0.05) / 0.95).margin(1e-4));
  REQUIRE(m.active_faults.size() == 1);
  CHECK(m.active_faults[0] == "stuck: stuck_at drive_y");
  SECTION("it ends after its duration") {
    REQUIRE_FALSE(panel.update(driving(), t0 + 150'000).has_value());
    REQUIRE_FALSE(panel.update(driving(), t0 + 300'000).has_value());
    REQUIRE_FALSE(panel.update(driving(), t0 + 450'000).has_value());
    REQUIRE_FALSE(panel.update(driving(), t0 + 600'000).has_value());
    m = panel.state("v", t0 + 601'000, 0);
    CHECK(axis(m, "drive_y") == Approx(1.0f).margin(1e-4));
    CHECK(m.active_faults.empty());
  }
  SECTION("a clear removes it") {
    c.action = "clear";
    c.fault_id = "";
    REQUIRE(panel.apply(c, t0 + 2'000) == "");
    m = panel.state("v", t0 + 3'000, 0);
    CHECK(axis(m, "drive_y") == Approx(1.0f).margin(1e-4));
    CHECK(m.active_faults.empty());
  }
  SECTION("another layer's fault or an unknown control is not taken") {
    c.kind = "can_drop";
    CHECK(panel.apply(c, t0) == "'can_drop' is not an input fault (a virtual panel has no wire)");
    c.kind = "stuck_at";
    c.target = "throttle";
    CHECK(panel.apply(c, t0) == "no control 'throttle' in panel 'rise-console'");
  }
  SECTION("a rejected command is reported for 10 s") {
    panel.note_rejected("unsigned", t0);
    m = panel.state("v", t0 + 1'000, 0);
    CHECK(std::find(m.active_faults.begin(), m.active_faults.end(), "rejected: unsigned") != m.active_faults.end());
    CHECK(panel.state("v", t0 + 10'001'000, 0).active_faults.empty());  // the note and the 0.5 s fault are over
  }
}
