#include "hil/feedback.hpp"

#include <cmath>
#include <limits>

namespace rise::hil {

int32_t display_raw(float value, uint8_t decimals) {
  const double scaled = std::round(static_cast<double>(value) * std::pow(10.0, decimals));
  if (!(scaled == scaled)) return 0;  // NaN shows as 0
  constexpr double lo = std::numeric_limits<int32_t>::min();
  constexpr double hi = std::numeric_limits<int32_t>::max();
  return static_cast<int32_t>(std::fmin(std::fmax(scaled, lo), hi));
}

FeedbackFrames build_feedback(const panels::PanelDefinition& definition, std::size_t source,
                              const FeedbackRequest& request, const PanelSnapshot& snapshot) {
  FeedbackFrames out;
  bool estop = false;
  for (std::size_t i = 0; i < definition.controls.size() && i < snapshot.controls.size(); ++i)
    if (definition.controls[i].role == panels::ControlRole::Estop && snapshot.controls[i].pressed &&
        !snapshot.controls[i].forced_safe)
      estop = true;

  for (const auto& led : definition.leds) {
    if (led.source != source) continue;
    bool on = false;
    if (led.name == "power") on = true;
    else if (led.name == "fault") on = snapshot.failsafe;
    else if (led.name == "estop") on = estop;
    for (const auto& [name, value] : request.leds)
      if (name == led.name) on = value;
    if (on) out.indicators.leds_on |= 1u << led.bit;
  }
  if (definition.buzzer_source && *definition.buzzer_source == source)
    out.indicators.buzzer = request.buzzer;

  for (const auto& display : definition.displays) {
    if (display.source != source) continue;
    firmware_protocol::DisplayFrame frame;
    frame.index = display.index;
    frame.decimals = display.decimals;
    for (const auto& [name, value] : request.displays)
      if (name == display.name) frame.raw = display_raw(value, display.decimals);
    out.displays.push_back(frame);
  }
  return out;
}

}  // namespace rise::hil
