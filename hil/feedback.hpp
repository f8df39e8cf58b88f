#pragma once

// Panel feedback (LEDs, displays, buzzer) by name → the frames of one source.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "firmware_protocol/console_can.hpp"
#include "hil/panel_mapper.hpp"
#include "panels/panel_definition.hpp"

namespace rise::hil {

/// What the simulator or instructor asked the console to show.
struct FeedbackRequest {
  std::vector<std::pair<std::string, bool>> leds;
  std::vector<std::pair<std::string, float>> displays;
  firmware_protocol::BuzzerMode buzzer = firmware_protocol::BuzzerMode::Off;
};

struct FeedbackFrames {
  firmware_protocol::IndicatorsFrame indicators;
  std::vector<firmware_protocol::DisplayFrame> displays;
};

/// Builds one source's feedback frames. The bridge owns three LEDs when no
/// request names them: "power" (lit while the daemon runs), "fault" (panel
/// in failsafe) and "estop" (e-stop pressed); a request overrides any LED by
/// name. Names the definition does not know are ignored.
FeedbackFrames build_feedback(const panels::PanelDefinition& definition, std::size_t source,
                              const FeedbackRequest& request, const PanelSnapshot& snapshot);

/// value → raw display units: round(value · 10^decimals), saturated to int32.
int32_t display_raw(float value, uint8_t decimals);

}  // namespace rise::hil
