#include "hil/panel_state_message.hpp"

#include <algorithm>
#include <cmath>

namespace rise::hil {
namespace fp = rise::firmware_protocol;

rise_msgs::PanelState to_message(const panels::PanelDefinition& definition,
                                 const PanelSnapshot& snapshot, const std::string& trainee_id,
                                 int64_t seq, int64_t utime,
                                 const std::vector<std::string>& source_urls) {
  rise_msgs::PanelState m;
  m.utime = utime;
  m.panel_id = definition.name;
  m.trainee_id = trainee_id;
  m.seq = seq;
  m.failsafe = snapshot.failsafe;
  m.failsafe_causes = snapshot.failsafe_causes.bits;
  m.failsafe_reason = snapshot.failsafe_reason;
  m.deadman = snapshot.deadman;
  for (std::size_t i = 0; i < definition.controls.size(); ++i) {
    const auto& c = definition.controls[i];
    const auto& v = snapshot.controls[i];
    switch (c.kind) {
      case panels::ControlKind::Axis: {
        rise_msgs::PanelAxis a;
        a.name = c.name;
        a.value = v.axis;
        m.axes.push_back(a);
        break;
      }
      case panels::ControlKind::Button: {
        rise_msgs::PanelButton b;
        b.name = c.name;
        b.pressed = v.pressed;
        m.buttons.push_back(b);
        break;
      }
      case panels::ControlKind::Switch: {
        rise_msgs::PanelSwitch s;
        s.name = c.name;
        s.position = static_cast<int8_t>(v.position);
        s.label = v.position < c.positions.size() ? c.positions[v.position] : "";
        m.switches.push_back(s);
        break;
      }
    }
  }
  for (std::size_t i = 0; i < snapshot.sources.size(); ++i) {
    const auto& s = snapshot.sources[i];
    rise_msgs::SourceHealth h;
    h.name = s.name;
    h.url = i < source_urls.size() ? source_urls[i] : "";
    h.connected = s.connected;
    h.stale = s.stale;
    h.last_frame_age_us = s.last_frame_age_us;
    h.frames_ok = s.frames_ok;
    h.frames_bad = s.frames_bad();
    const auto count = [&](fp::DecodeError e) {
      return static_cast<int32_t>(s.errors[static_cast<std::size_t>(e)]);
    };
    h.crc_errors = count(fp::DecodeError::BadCrc);
    h.counter_errors = count(fp::DecodeError::RepeatedCounter) + count(fp::DecodeError::SkippedCounter);
    h.length_errors = count(fp::DecodeError::BadLength);
    h.unknown_ids = count(fp::DecodeError::UnknownId);
    h.reconnects = s.reconnects;
    h.timeouts = static_cast<int32_t>(s.timeouts);
    h.exceptions = static_cast<int32_t>(s.exceptions);
    // A console that has not said its status (or has no heartbeat) shows "".
    h.status = s.heartbeat_seen ? fp::to_string(s.console_status) : "";
    h.error_frames = static_cast<int32_t>(s.error_frames);
    // Only CAN sources have a controller state, and only while their
    // transport is open: a bus that never opened has none to report.
    const bool can = i < definition.sources.size() && !definition.sources[i].is_modbus() && !definition.sources[i].is_hid();
    h.bus_state = can && s.connected ? std::string(io::to_string(s.bus_state)) : "";
    h.down_reason = s.connected ? "" : !s.down_reason.empty() ? s.down_reason
                    : s.ever_connected     ? "disconnected"
                                           : "not connected yet";
    h.bus_offs = s.bus_offs;
    m.sources.push_back(h);
  }
  m.num_axes = static_cast<int16_t>(m.axes.size());
  m.num_buttons = static_cast<int16_t>(m.buttons.size());
  m.num_switches = static_cast<int16_t>(m.switches.size());
  m.num_sources = static_cast<int16_t>(m.sources.size());
  m.active_faults = snapshot.active_faults;
  m.num_faults = static_cast<int16_t>(m.active_faults.size());
  return m;
}

FeedbackRequest from_message(const rise_msgs::PanelFeedback& message) {
  FeedbackRequest r;
  const auto leds = std::min<std::size_t>({static_cast<std::size_t>(std::max<int16_t>(message.num_leds, 0)),
                                           message.led_names.size(), message.led_on.size()});
  for (std::size_t i = 0; i < leds; ++i) r.leds.emplace_back(message.led_names[i], message.led_on[i]);
  const auto displays =
      std::min<std::size_t>({static_cast<std::size_t>(std::max<int16_t>(message.num_displays, 0)),
                             message.display_names.size(), message.display_values.size()});
  for (std::size_t i = 0; i < displays; ++i)
    r.displays.emplace_back(message.display_names[i], message.display_values[i]);
  r.rumble = std::isfinite(message.rumble) ? std::clamp(message.rumble, 0.0f, 1.0f) : 0.0f;
  r.buzzer = message.buzzer == 1   ? fp::BuzzerMode::On
             : message.buzzer == 2 ? fp::BuzzerMode::Beep
                                   : fp::BuzzerMode::Off;
  return r;
}

}  // namespace rise::hil
