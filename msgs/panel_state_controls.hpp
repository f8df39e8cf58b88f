#pragma once

// A PanelState's controls by name: the value of an axis, a button or a
// switch, for the programs and tests that watch one control of the panel.

#include <optional>
#include <string>

#include "rise_msgs/PanelState.hpp"

namespace rise::msgs {

/// The value of the axis `name`; nullopt when the message has none.
std::optional<float> find_axis(const rise_msgs::PanelState& state, const std::string& name);
/// Whether the button `name` is pressed; nullopt when the message has none.
std::optional<bool> find_button(const rise_msgs::PanelState& state, const std::string& name);
/// The label of the switch `name`'s position; nullopt when the message has none.
std::optional<std::string> find_switch_label(const rise_msgs::PanelState& state, const std::string& name);

}  // namespace rise::msgs
