#include "instructor/fault_presets.hpp"

#include <algorithm>

namespace rise::instructor {

const std::vector<FaultPreset>& default_fault_presets() {
  // Input faults act on the rise console's controls, wire faults on its
  // source "console", transport faults on panel_state, physics and sensor
  // faults on the robot (rise-sim).
  static const std::vector<FaultPreset> presets = {
      {"stick-stuck", "drive stick stuck at 0.6", "stuck_at", "drive_y", 0.6, 0.0, 0.0},
      {"stick-drift", "drive stick drifts right", "drift", "drive_x", 0.0, 0.2, 0.0},
      {"stick-noise", "drive stick noise", "noise", "drive_y", 0.1, 0.0, 0.0},
      {"deadman-intermittent", "dead-man intermittent", "intermittent", "deadman", 0.5, 0.1, 0.0},
      {"can-drop", "CAN frames dropped (50 %)", "can_drop", "console", 0.5, 0.0, 0.0},
      {"can-bus-off", "CAN bus-off", "can_bus_off", "console", 0.0, 0.0, 5.0},
      {"lcm-loss", "PanelState loss (30 %)", "lcm_loss", "panel_state", 0.3, 0.0, 0.0},
      {"left-motor", "left motor failure", "motor_failure", "left", 0.0, 0.0, 0.0},
      {"track-slip", "track slip", "track_slip", "left", 0.5, 0.0, 0.0},
      {"camera-blackout", "camera blackout", "camera_blackout", "", 0.0, 0.0, 10.0},
  };
  return presets;
}

const FaultPreset* find_fault_preset(const std::string& id) {
  const auto& presets = default_fault_presets();
  const auto it = std::find_if(presets.begin(), presets.end(), [&](const FaultPreset& p) { return p.id == id; });
  return it == presets.end() ? nullptr : &*it;
}

}  // namespace rise::instructor
