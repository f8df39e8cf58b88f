// A PanelState's controls by name: found, or nullopt when the message has none.

#include <catch2/catch.hpp>

#include "msgs/panel_state_controls.hpp"

namespace {

rise_msgs::PanelState state() {
  rise_msgs::PanelState m{};
  rise_msgs::PanelAxis drive{};
  drive.name = "drive_y";
  drive.value = 0.5f;
  m.axes.push_back(drive);
  m.num_axes = 1;
  rise_msgs::PanelButton deadman{};
  deadman.name = "deadman";
  deadman.pressed = true;
  m.buttons.push_back(deadman);
  m.num_buttons = 1;
  rise_msgs::PanelSwitch speed{};
  speed.name = "speed";
  speed.label = "slow";
  m.switches.push_back(speed);
  m.num_switches = 1;
  return m;
}

}  // namespace

TEST_CASE("a PanelState's axis, button and switch are found by name", "[msgs]") {
  const auto m = state();
  CHECK(rise::msgs::find_axis(m, "drive_y") == 0.5f);
  CHECK(rise::msgs::find_button(m, "deadman") == true);
  CHECK(rise::msgs::find_switch_label(m, "speed") == "slow");
}

TEST_CASE("a control the PanelState does not carry is nullopt", "[msgs]") {
  const auto m = state();
  CHECK_FALSE(rise::msgs::find_axis(m, "drive_x").has_value());
  CHECK_FALSE(rise::msgs::find_button(m, "horn").has_value());
  CHECK_FALSE(rise::msgs::find_switch_label(m, "drive_y").has_value());
}
