#include "hil/feedback.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "firmware_protocol/canopen_eds.hpp"
#include "firmware_protocol/dbc.hpp"

namespace rise::hil {

int32_t display_raw(float value, uint8_t decimals) {
  const double scaled = std::round(static_cast<double>(value) * std::pow(10.0, decimals));
  if (!(scaled == scaled)) return 0;  // NaN shows as 0
  constexpr double lo = std::numeric_limits<int32_t>::min();
  constexpr double hi = std::numeric_limits<int32_t>::max();
  return static_cast<int32_t>(std::fmin(std::fmax(scaled, lo), hi));
}

namespace {

// The e-stop as the panel reads it: pressed by a person, not forced safe.
bool estop_pressed(const panels::PanelDefinition& definition, const PanelSnapshot& snapshot) {
  for (std::size_t i = 0; i < definition.controls.size() && i < snapshot.controls.size(); ++i)
    if (definition.controls[i].role == panels::ControlRole::Estop && snapshot.controls[i].pressed &&
        !snapshot.controls[i].forced_safe)
      return true;
  return false;
}

bool lit(const panels::LedDefinition& led, const FeedbackRequest& request, const PanelSnapshot& snapshot,
         bool estop) {
  bool on = false;
  if (led.name == "power") on = true;
  else if (led.name == "fault") on = snapshot.failsafe;
  else if (led.name == "estop") on = estop;
  for (const auto& [name, value] : request.leds)
    if (name == led.name) on = value;
  return on;
}

}  // namespace

FeedbackFrames build_feedback(const panels::PanelDefinition& definition, std::size_t source,
                              const FeedbackRequest& request, const PanelSnapshot& snapshot) {
  FeedbackFrames out;
  const bool estop = estop_pressed(definition, snapshot);
  for (const auto& led : definition.leds) {
    if (led.source != source) continue;
    if (lit(led, request, snapshot, estop)) out.indicators.leds_on |= 1u << led.bit;
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

std::vector<ModbusWrite> build_modbus_feedback(const panels::PanelDefinition& definition, std::size_t source,
                                               const FeedbackRequest& request, const PanelSnapshot& snapshot) {
  std::vector<ModbusWrite> out;
  const bool estop = estop_pressed(definition, snapshot);
  for (const auto& led : definition.leds)
    if (led.source == source && led.modbus_point)
      out.push_back({*led.modbus_point, static_cast<uint16_t>(lit(led, request, snapshot, estop) ? 1 : 0)});
  for (const auto& display : definition.displays) {
    if (display.source != source || !display.modbus_point) continue;
    int32_t raw = 0;
    for (const auto& [name, value] : request.displays)
      if (name == display.name) raw = display_raw(value, display.decimals);
    const bool int16 = display.modbus_type == panels::ModbusValueType::Int16;
    raw = std::clamp<int32_t>(raw, int16 ? -32768 : 0, int16 ? 32767 : 65535);
    out.push_back({*display.modbus_point, static_cast<uint16_t>(raw)});
  }
  return out;
}

namespace {
// A display's raw value saturated to what the object's bits hold.
uint64_t saturated_raw(const firmware_protocol::DbcSignal& signal, int32_t raw) {
  const uint32_t bits = std::min<uint32_t>(signal.length_bits, 63);
  const int64_t lo = signal.is_signed ? -(int64_t{1} << (bits - 1)) : 0;
  const int64_t hi = signal.is_signed ? (int64_t{1} << (bits - 1)) - 1 : (int64_t{1} << bits) - 1;
  return static_cast<uint64_t>(std::clamp<int64_t>(raw, lo, hi));
}
}  // namespace

std::vector<firmware_protocol::canopen::Frame> build_canopen_feedback(const panels::PanelDefinition& definition,
                                                                      std::size_t source,
                                                                      const FeedbackRequest& request,
                                                                      const PanelSnapshot& snapshot) {
  std::vector<firmware_protocol::canopen::Frame> frames;
  const panels::SourceDefinition& def = definition.sources[source];
  if (!def.eds) return frames;
  const bool estop = estop_pressed(definition, snapshot);
  for (const firmware_protocol::DbcMessage& rpdo : def.eds->rpdo_messages()) {
    firmware_protocol::canopen::Frame frame;
    frame.cob_id = rpdo.id;
    frame.extended = rpdo.extended;
    frame.len = std::min<uint8_t>(rpdo.dlc, 8);
    const std::span<uint8_t> data(frame.data.data(), frame.len);
    bool used = false;
    for (const auto& led : definition.leds)
      if (led.source == source && led.pdo_message == &rpdo) {
        firmware_protocol::insert_raw(*led.pdo_signal, lit(led, request, snapshot, estop) ? 1 : 0, data);
        used = true;
      }
    for (const auto& display : definition.displays) {
      if (display.source != source || display.pdo_message != &rpdo) continue;
      int32_t raw = 0;
      for (const auto& [name, value] : request.displays)
        if (name == display.name) raw = display_raw(value, display.decimals);
      firmware_protocol::insert_raw(*display.pdo_signal, saturated_raw(*display.pdo_signal, raw), data);
      used = true;
    }
    if (used) frames.push_back(frame);
  }
  return frames;
}

std::vector<std::vector<uint8_t>> build_hid_feedback(const panels::PanelDefinition& definition, std::size_t source,
                                                     const FeedbackRequest& request, const PanelSnapshot& snapshot,
                                                     const firmware_protocol::HidOutputEncoder& encoder) {
  const bool estop = estop_pressed(definition, snapshot);
  const bool ids = encoder.descriptor().uses_report_ids;
  std::vector<std::vector<uint8_t>> reports;
  std::vector<uint8_t> report_ids;  // of reports[i]
  // Writes `value` (normalised) into the named output signal's report.
  const auto put = [&](const std::string& name, double value) {
    const std::size_t signal = encoder.find(name);
    if (signal >= encoder.signals().size()) return;
    const firmware_protocol::HidSignal& s = encoder.signals()[signal];
    std::size_t r = 0;
    while (r < report_ids.size() && report_ids[r] != s.report_id) ++r;
    if (r == report_ids.size()) {
      // hidraw takes the report id first; 0 stands first when there are none.
      reports.emplace_back(encoder.report_length(s.report_id) + (ids ? 0 : 1), uint8_t{0});
      report_ids.push_back(s.report_id);
    }
    const std::span<uint8_t> data = ids ? std::span<uint8_t>(reports[r]) : std::span<uint8_t>(reports[r]).subspan(1);
    encoder.encode(signal, firmware_protocol::hid_raw_from_value(s, value), data);
  };
  for (const auto& led : definition.leds)
    if (led.source == source && !led.hid_signal.empty())
      put(led.hid_signal, lit(led, request, snapshot, estop) ? 1.0 : 0.0);
  for (const auto& rumble : definition.rumbles)
    if (rumble.source == source) put(rumble.hid_signal, static_cast<double>(request.rumble));
  return reports;
}

std::vector<std::string> hid_feedback_problems(const panels::PanelDefinition& definition, std::size_t source,
                                               const firmware_protocol::HidOutputEncoder& encoder) {
  std::vector<std::string> problems;
  const auto check = [&](const char* kind, const std::string& name, const std::string& signal, int line) {
    if (encoder.find(signal) < encoder.signals().size()) return;
    const std::string known = firmware_protocol::hid_signal_names(encoder.signals());
    problems.push_back(definition.file + ":" + std::to_string(line) + ": feedback." + kind + "." + name +
                       ".signal: the device has no output signal '" + signal + "' (" +
                       (known.empty() ? std::string("it has no output report") : "its output signals: " + known) +
                       ")");
  };
  for (const auto& led : definition.leds)
    if (led.source == source && !led.hid_signal.empty()) check("leds", led.name, led.hid_signal, led.line);
  for (const auto& rumble : definition.rumbles)
    if (rumble.source == source) check("rumble", rumble.name, rumble.hid_signal, rumble.line);
  return problems;
}

}  // namespace rise::hil
