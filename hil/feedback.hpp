#pragma once

// Panel feedback (LEDs, displays, buzzer) by name → the frames of one source.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "firmware_protocol/canopen.hpp"
#include "firmware_protocol/console_can.hpp"
#include "firmware_protocol/hid_report.hpp"
#include "hil/panel_mapper.hpp"
#include "panels/panel_definition.hpp"

namespace rise::hil {

/// What the simulator or instructor asked the console to show.
struct FeedbackRequest {
  std::vector<std::pair<std::string, bool>> leds;
  std::vector<std::pair<std::string, float>> displays;
  firmware_protocol::BuzzerMode buzzer = firmware_protocol::BuzzerMode::Off;
  float rumble = 0.0f;  ///< 0..1: written to the definition's rumble signals (hid sources)
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

/// The output reports that show a hid source's LEDs: every LED of `source`
/// bound to an output signal (`signal:`) lit or dark as build_feedback
/// decides for the LEDs of a CAN console, every
/// other output field 0. One report per output report that carries such an
/// LED, as HidDevice::write takes it (id byte first; 0 when the device uses
/// no report ids). LEDs whose signal the device lacks are left out (see
/// hid_feedback_problems); a device without output reports gets none.
/// Allocates: call at the feedback rate, not per input report.
std::vector<std::vector<uint8_t>> build_hid_feedback(const panels::PanelDefinition& definition, std::size_t source,
                                                     const FeedbackRequest& request, const PanelSnapshot& snapshot,
                                                     const firmware_protocol::HidOutputEncoder& encoder);

/// One line per LED of `source` that this device cannot show
/// ("panel.yaml:12: feedback.leds.power.signal: the device has no output
/// signal 'usage_0008_0009' (its output signals: ...)"); empty when it can
/// show them all. Allocates: call when the device is opened.
std::vector<std::string> hid_feedback_problems(const panels::PanelDefinition& definition, std::size_t source,
                                               const firmware_protocol::HidOutputEncoder& encoder);

/// What shows a "modbus" source's feedback: each LED of `source` (lit as
/// build_feedback decides) as 1 / 0 on its coil or holding register, then
/// each display as its raw value (value · 10^decimals) saturated to its
/// type (uint16: 0..65535, int16: -32768..32767), in the definition's order.
/// Allocates: call at the feedback rate.
std::vector<ModbusWrite> build_modbus_feedback(const panels::PanelDefinition& definition, std::size_t source,
                                               const FeedbackRequest& request, const PanelSnapshot& snapshot);

/// The RPDOs that show a "canopen" source's feedback: one frame per RPDO
/// that maps an LED or display of `source`, of the RPDO's length, every
/// mapped object 0 but each LED (1 lit, as build_feedback decides) and
/// each display (value · 10^decimals, saturated to the object's type), in
/// the EDS's RPDO order. Allocates: call at the feedback rate.
std::vector<firmware_protocol::canopen::Frame> build_canopen_feedback(const panels::PanelDefinition& definition,
                                                                      std::size_t source,
                                                                      const FeedbackRequest& request,
                                                                      const PanelSnapshot& snapshot);

/// value → raw display units: round(value · 10^decimals), saturated to int32.
int32_t display_raw(float value, uint8_t decimals);

}  // namespace rise::hil
