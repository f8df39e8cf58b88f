#include "msgs/panel_state_controls.hpp"

namespace rise::msgs {

std::optional<float> find_axis(const rise_msgs::PanelState& state, const std::string& name) {
  for (const auto& a : state.axes)
    if (a.name == name) return a.value;
  return std::nullopt;
}

std::optional<bool> find_button(const rise_msgs::PanelState& state, const std::string& name) {
  for (const auto& b : state.buttons)
    if (b.name == name) return b.pressed != 0;
  return std::nullopt;
}

std::optional<std::string> find_switch_label(const rise_msgs::PanelState& state, const std::string& name) {
  for (const auto& s : state.switches)
    if (s.name == name) return s.label;
  return std::nullopt;
}

}  // namespace rise::msgs
