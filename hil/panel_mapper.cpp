#include "hil/panel_mapper.hpp"

#include "firmware_protocol/canopen_eds.hpp"
#include "firmware_protocol/dbc.hpp"
#include "firmware_protocol/j1939.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

namespace rise::hil {
namespace {

namespace fp = rise::firmware_protocol;
using panels::ControlKind;
using panels::ControlRole;
using panels::SignalRef;

constexpr std::size_t type_index(fp::FrameType t) { return static_cast<std::size_t>(t); }

fp::FrameType frame_type_for(const SignalRef& signal) {
  switch (signal.kind) {
    case SignalRef::Kind::Axis:
      return signal.index < fp::kAxesPerFrame ? fp::FrameType::Axes0 : fp::FrameType::Axes1;
    case SignalRef::Kind::Button: return fp::FrameType::Buttons;
    case SignalRef::Kind::Switch: return fp::FrameType::Switches;
  }
  return fp::FrameType::Axes0;
}


void set_safe(const panels::ControlDefinition& c, ControlValue& v) {
  v.axis = c.safe_axis;
  v.pressed = c.safe_button;
  v.position = c.safe_switch;
  v.forced_safe = true;
}

}  // namespace

int64_t SourceStatus::frames_bad() const {
  int64_t sum = 0;
  for (std::size_t i = 0; i < errors.size(); ++i)
    if (static_cast<fp::DecodeError>(i) != fp::DecodeError::None) sum += errors[i];
  return sum;
}

int64_t heartbeat_timeout_us(const panels::SourceDefinition& source) {
  const int64_t three_periods_ms = 3 * fp::nominal_period_ms(fp::FrameType::Heartbeat);
  return 1000 * std::max<int64_t>(three_periods_ms, source.timeout_ms);
}

PanelMapper::PanelMapper(panels::PanelDefinition definition) : definition_(std::move(definition)) {
  sources_.reserve(definition_.sources.size());
  for (const auto& s : definition_.sources) {
    SourceState state(fp::Decoder(s.node, s.max_counter_delta));
    state.status.name = s.name;
    sources_.push_back(std::move(state));
  }
  for (const auto& c : definition_.controls) {
    if (c.dbc_signal) {
      SignalBinding b;
      b.message = c.dbc_message;
      b.signal = c.dbc_signal;
      if (c.dbc_signal->is_multiplexed)
        for (const auto& other : c.dbc_message->signals)
          if (other.is_multiplexer) b.multiplexer = &other;
      binding_of_control_.push_back(static_cast<int>(sources_[c.source].bindings.size()));
      sources_[c.source].bindings.push_back(b);
    } else if (!c.hid_signal.empty() || c.modbus_point) {
      SignalBinding b;
      b.hid_raw = c.kind == ControlKind::Switch;
      b.modbus = c.modbus_point;
      b.modbus_type = c.modbus_type;
      binding_of_control_.push_back(static_cast<int>(sources_[c.source].bindings.size()));
      sources_[c.source].bindings.push_back(b);
    } else {
      binding_of_control_.push_back(-1);
      sources_[c.source].needs_type[type_index(frame_type_for(c.signal))] = true;
    }
    const ButtonMode mode = c.behaviour == panels::ButtonBehaviour::Toggle      ? ButtonMode::Toggle
                            : c.behaviour == panels::ButtonBehaviour::LongPress ? ButtonMode::LongPress
                            : c.behaviour == panels::ButtonBehaviour::Edge      ? ButtonMode::Edge
                                                                                : ButtonMode::Direct;
    filters_.push_back({LowPass(c.lowpass_ms), ButtonFilter({mode, c.debounce_ms, c.long_press_ms, c.pulse_ms}),
                        true, std::nullopt});
  }
}

bool PanelMapper::on_dbc_frame(SourceState& s, uint32_t can_id, bool extended, std::span<const uint8_t> data,
                               int64_t now_us, bool j1939) {
  bool matched = false, changed = false, bad = false;
  for (SignalBinding& b : s.bindings) {
    // A J1939 message is its PGN, whatever priority and addresses the DBC's
    // id holds (the source already took only the console's).
    const bool same_id = j1939 ? fp::j1939::pgn_of(b.message->id) == fp::j1939::pgn_of(can_id)
                               : b.message->id == can_id;
    if (!same_id || b.message->extended != extended) continue;
    matched = true;
    if (!fp::signal_fits(*b.signal, data.size()) ||
        (b.multiplexer && !fp::signal_fits(*b.multiplexer, data.size()))) {
      bad = true;
      continue;
    }
    if (b.multiplexer && static_cast<uint64_t>(fp::extract_raw(*b.multiplexer, data)) != b.signal->multiplexer_value)
      continue;  // this frame carries another multiplexed page
    changed = take(b, fp::physical_value(*b.signal, fp::extract_raw(*b.signal, data)), now_us) || changed;
  }
  if (!matched) {
    s.status.errors[static_cast<std::size_t>(fp::DecodeError::UnknownId)]++;
    return false;
  }
  if (bad) {
    // A frame too short for a bound signal: the device does not match its DBC.
    s.status.errors[static_cast<std::size_t>(fp::DecodeError::BadLength)]++;
    s.status.check_failed = true;
    s.ok_in_row = 0;
    return false;
  }
  s.status.errors[static_cast<std::size_t>(fp::DecodeError::None)]++;
  s.status.frames_ok++;
  s.last_any_valid_us = now_us;
  count_valid(s);
  return changed;
}

bool PanelMapper::on_canopen_frame(SourceState& s, const panels::SourceDefinition& def, uint32_t can_id,
                                   bool extended, std::span<const uint8_t> data, int64_t now_us) {
  namespace co = fp::canopen;
  const co::HeartbeatResult hb = extended ? co::HeartbeatResult{} : co::read_heartbeat(def.node, can_id, data);
  switch (hb.read) {
    case co::HeartbeatRead::NotHeartbeat: break;
    case co::HeartbeatRead::BadLength: s.status.errors[static_cast<std::size_t>(fp::DecodeError::BadLength)]++; return false;
    case co::HeartbeatRead::BadState: s.status.errors[static_cast<std::size_t>(fp::DecodeError::BadValue)]++; return false;
    case co::HeartbeatRead::Ok: {
      const bool changed = !s.status.heartbeat_seen || hb.state != s.nmt_state;
      // Outside Operational the node sends no PDOs (CiA 301 §7.3.2.2.4): what
      // it sent before is no state to trust once it is back, so each bound
      // object waits for a PDO sent since.
      if (hb.state != co::NmtState::Operational)
        for (auto& b : s.bindings) b.last_us = 0;
      s.nmt_state = hb.state;
      s.heartbeat_us = now_us;
      s.status.heartbeat_seen = true;
      s.status.errors[static_cast<std::size_t>(fp::DecodeError::None)]++;
      s.status.frames_ok++;
      s.last_any_valid_us = now_us;
      return changed;
    }
  }
  const auto& tpdos = def.eds->tpdo_messages();
  const bool is_tpdo = std::any_of(tpdos.begin(), tpdos.end(),
                                   [&](const fp::DbcMessage& m) { return m.id == can_id && m.extended == extended; });
  if (!is_tpdo) {
    // SYNC, NMT, other nodes: the bus is shared.
    s.status.errors[static_cast<std::size_t>(fp::DecodeError::UnknownId)]++;
    return false;
  }
  // Taken once the node was heard, whatever state its last heartbeat said: a
  // node sends PDOs only in Operational (so one after a boot-up means it was
  // started), and canopen_trouble() trusts the values only while the
  // heartbeat says Operational.
  if (!s.status.heartbeat_seen) return false;
  bool changed = false;
  for (SignalBinding& b : s.bindings) {
    if (b.message->id != can_id || b.message->extended != extended) continue;
    if (!fp::signal_fits(*b.signal, data.size())) {
      // Shorter than its mapping: CiA 301 §7.2.2.2 has the node discard it
      // (EMCY 0x8210); so does the bridge, counted and failing the check.
      s.status.errors[static_cast<std::size_t>(fp::DecodeError::BadLength)]++;
      s.status.check_failed = true;
      s.ok_in_row = 0;
      return false;
    }
    changed = take(b, fp::physical_value(*b.signal, fp::extract_raw(*b.signal, data)), now_us) || changed;
  }
  s.status.errors[static_cast<std::size_t>(fp::DecodeError::None)]++;
  s.status.frames_ok++;
  s.last_any_valid_us = now_us;
  count_valid(s);
  return changed;
}

// A valid frame or block: recovery from a failed protection check.
void PanelMapper::count_valid(SourceState& s) {
  const uint32_t recovery = definition_.sources[static_cast<std::size_t>(&s - sources_.data())].recovery_frames;
  if (s.status.check_failed && ++s.ok_in_row >= recovery) s.status.check_failed = false;
}

bool PanelMapper::on_bus_error(std::size_t source, const io::CanErrorReport& report, int64_t now_us) {
  (void)now_us;
  if (source >= sources_.size()) return false;
  SourceState& s = sources_[source];
  s.status.error_frames++;
  if (!report.state || *report.state == s.status.bus_state) return false;
  if (*report.state == io::CanBusState::BusOff) s.status.bus_offs++;
  s.status.bus_state = *report.state;
  return true;
}

bool PanelMapper::attach_hid(std::size_t source, std::span<const uint8_t> descriptor, std::string* error) {
  if (source >= sources_.size()) return false;
  SourceState& s = sources_[source];
  const std::string& name = definition_.sources[source].name;
  s.hid.reset();
  s.named = 0;
  s.hid_last_us = 0;
  auto fail = [&](std::string message) {
    s.hid_error = name + ": " + std::move(message);
    if (error) *error = s.hid_error;
    return false;
  };
  fp::HidParseResult parsed = fp::parse_hid_descriptor(descriptor);
  if (!parsed)
    return fail("report descriptor does not parse (" + std::string(fp::to_string(parsed.error)) + " at byte " +
                std::to_string(parsed.error_offset) + ")");
  auto decoder = std::make_unique<fp::HidReportDecoder>(std::move(parsed.descriptor));
  for (std::size_t i = 0; i < definition_.controls.size(); ++i) {
    const auto& c = definition_.controls[i];
    if (c.source != source || c.hid_signal.empty()) continue;
    const std::size_t index = decoder->find(c.hid_signal);
    if (index >= decoder->signals().size()) {
      return fail("control '" + c.name + "': the device has no signal '" + c.hid_signal +
                  "' (it has: " + fp::hid_signal_names(decoder->signals()) + ")");
    }
    SignalBinding& b = s.bindings[static_cast<std::size_t>(binding_of_control_[i])];
    b.hid_signal = index;
    b.last_us = 0;
  }
  s.hid_values.assign(decoder->signals().size(), fp::HidSignalValue{});
  s.hid = std::move(decoder);
  s.hid_error.clear();
  return true;
}

bool PanelMapper::attach_named(std::size_t source, std::span<const std::string> names, std::string* error,
                               const std::string& missing_note) {
  if (source >= sources_.size()) return false;
  SourceState& s = sources_[source];
  s.hid.reset();
  s.named = 0;
  s.hid_last_us = 0;
  for (std::size_t i = 0; i < definition_.controls.size(); ++i) {
    const auto& c = definition_.controls[i];
    if (c.source != source || c.hid_signal.empty()) continue;
    const auto it = std::find(names.begin(), names.end(), c.hid_signal);
    if (it == names.end()) {
      std::string known;
      for (std::size_t n = 0; n < names.size() && n < 24; ++n) known += (n ? ", " : "") + names[n];
      s.hid_error = definition_.sources[source].name + ": control '" + c.name + "': the device has no signal '" +
                    c.hid_signal + "'" + missing_note + " (it has: " + known + (names.size() > 24 ? ", ..." : "") + ")";
      if (error) *error = s.hid_error;
      return false;
    }
    SignalBinding& b = s.bindings[static_cast<std::size_t>(binding_of_control_[i])];
    b.hid_signal = static_cast<std::size_t>(it - names.begin());
    b.last_us = 0;
  }
  s.named = names.size();
  s.hid_error.clear();
  return true;
}

bool PanelMapper::on_named_values(std::size_t source, std::span<const double> values, int64_t now_us) {
  if (source >= sources_.size()) return false;
  SourceState& s = sources_[source];
  if (s.named == 0 || values.size() < s.named) return false;
  bool changed = false;
  for (SignalBinding& b : s.bindings) changed = take(b, values[b.hid_signal], now_us) || changed;
  s.status.errors[static_cast<std::size_t>(fp::DecodeError::None)]++;
  s.status.frames_ok++;
  s.last_any_valid_us = now_us;
  s.hid_last_us = now_us;
  return changed;
}

void PanelMapper::on_named_alive(std::size_t source, int64_t now_us) {
  if (source >= sources_.size() || sources_[source].named == 0 || sources_[source].hid_last_us == 0) return;
  SourceState& s = sources_[source];
  for (SignalBinding& b : s.bindings) b.last_us = now_us;
  s.hid_last_us = now_us;
}

bool PanelMapper::on_hid_report(std::size_t source, std::span<const uint8_t> report, int64_t now_us) {
  if (source >= sources_.size()) return false;
  SourceState& s = sources_[source];
  if (!s.hid) return false;
  switch (s.hid->decode(report, s.hid_values)) {
    case fp::HidDecodeStatus::Ok: break;
    case fp::HidDecodeStatus::UnknownReportId:
      s.status.errors[static_cast<std::size_t>(fp::DecodeError::UnknownId)]++;
      return false;
    case fp::HidDecodeStatus::TooShort:
    case fp::HidDecodeStatus::BufferTooSmall:
      s.status.errors[static_cast<std::size_t>(fp::DecodeError::BadLength)]++;
      return false;
  }
  bool changed = false;
  for (SignalBinding& b : s.bindings) {
    const fp::HidSignalValue& v = s.hid_values[b.hid_signal];
    const double value = b.hid_raw ? static_cast<double>(v.raw) : v.value;
    changed = changed || b.last_us == 0 || value != b.value;
    b.value = value;
    b.last_us = now_us;
  }
  s.status.errors[static_cast<std::size_t>(fp::DecodeError::None)]++;
  s.status.frames_ok++;
  s.last_any_valid_us = now_us;
  s.hid_last_us = now_us;
  return changed;
}

bool PanelMapper::take(SignalBinding& b, double value, int64_t now_us) {
  const bool changed = b.last_us == 0 || value != b.value;
  b.value = value;
  b.last_us = now_us;
  return changed;
}

bool PanelMapper::on_modbus_poll(std::size_t source, const ModbusPoll& poll, int64_t now_us) {
  if (source >= sources_.size()) return false;
  SourceState& s = sources_[source];
  s.poll_last_us = s.last_any_valid_us = now_us;
  s.status.frames_ok++;
  s.status.errors[static_cast<std::size_t>(fp::DecodeError::None)]++;
  bool changed = false;
  for (SignalBinding& b : s.bindings)
    if (const std::optional<uint16_t> raw = b.modbus ? poll.value(*b.modbus) : std::nullopt)
      changed = take(b, b.modbus->is_bit() ? *raw : panels::modbus_number(*raw, b.modbus_type), now_us) || changed;
  return changed;
}

bool PanelMapper::on_frame(std::size_t source, uint32_t can_id, std::span<const uint8_t> data,
                           int64_t now_us, bool extended) {
  if (source >= sources_.size()) return false;
  SourceState& s = sources_[source];
  if (definition_.sources[source].is_canopen())
    return on_canopen_frame(s, definition_.sources[source], can_id, extended, data, now_us);
  if (definition_.sources[source].is_dbc())
    return on_dbc_frame(s, can_id, extended, data, now_us, definition_.sources[source].is_j1939());
  if (extended) {
    s.status.errors[static_cast<std::size_t>(fp::DecodeError::UnknownId)]++;
    return false;
  }
  const fp::DecodeResult r = s.decoder.decode(can_id, data);
  s.status.errors[static_cast<std::size_t>(r.error)]++;
  if (!r.ok()) {
    // Frames of other nodes and of our own feedback share the bus: an unknown
    // id is counted but is no failed check. Anything else on our ids is.
    if (r.error != fp::DecodeError::UnknownId) {
      s.status.check_failed = true;
      s.ok_in_row = 0;
    }
    return false;
  }
  if (r.type == fp::FrameType::Indicators || r.type == fp::FrameType::Display) return false;

  s.status.frames_ok++;
  s.last_valid_us[type_index(r.type)] = now_us;
  s.last_any_valid_us = now_us;
  count_valid(s);

  bool changed = false;
  if (const auto* axes = std::get_if<fp::AxesFrame>(&r.message)) {
    const std::size_t group = r.type == fp::FrameType::Axes0 ? 0 : 1;
    for (std::size_t i = 0; i < fp::kAxesPerFrame; ++i) {
      int16_t& slot = s.axes[group * fp::kAxesPerFrame + i];
      changed = changed || slot != axes->raw[i] || !s.axes_seen[group];
      slot = axes->raw[i];
    }
    s.axes_seen[group] = true;
  } else if (const auto* buttons = std::get_if<fp::ButtonsFrame>(&r.message)) {
    changed = s.buttons != buttons->pressed || !s.buttons_seen;
    s.buttons = buttons->pressed;
    s.buttons_seen = true;
  } else if (const auto* switches = std::get_if<fp::SwitchesFrame>(&r.message)) {
    changed = s.switches != switches->position || !s.switches_seen;
    s.switches = switches->position;
    s.switches_seen = true;
  } else if (const auto* hb = std::get_if<fp::HeartbeatFrame>(&r.message)) {
    changed = !s.status.heartbeat_seen || s.status.console_status != hb->status;
    s.status.console_status = hb->status;
    s.status.heartbeat_seen = true;
    s.protocol_version = hb->protocol_version;
  }
  return changed;
}

bool PanelMapper::on_inputs(std::size_t source, const fp::ConsoleInputs& in, int64_t now_us) {
  if (source >= sources_.size()) return false;
  SourceState& s = sources_[source];
  s.status.errors[static_cast<std::size_t>(fp::DecodeError::None)]++;
  s.status.frames_ok++;
  // One block carries what a CAN cycle spreads over five frame types.
  for (const auto t : {fp::FrameType::Axes0, fp::FrameType::Axes1, fp::FrameType::Buttons, fp::FrameType::Switches,
                       fp::FrameType::Heartbeat})
    s.last_valid_us[type_index(t)] = now_us;
  s.last_any_valid_us = now_us;
  count_valid(s);

  const bool changed = s.axes != in.axes || s.buttons != in.buttons || s.switches != in.switches ||
                       !s.axes_seen[0] || !s.buttons_seen || !s.switches_seen || !s.status.heartbeat_seen ||
                       s.status.console_status != in.status;
  s.axes = in.axes;
  s.buttons = in.buttons;
  s.switches = in.switches;
  s.axes_seen[0] = s.axes_seen[1] = true;
  s.buttons_seen = s.switches_seen = true;
  s.status.console_status = in.status;
  s.status.heartbeat_seen = true;
  s.protocol_version = in.protocol_version;
  return changed;
}

void PanelMapper::on_source_error(std::size_t source, SourceError kind, int64_t now_us) {
  (void)now_us;
  if (source >= sources_.size()) return;
  SourceState& s = sources_[source];
  auto count = [&](fp::DecodeError e) { s.status.errors[static_cast<std::size_t>(e)]++; };
  switch (kind) {
    case SourceError::BadCrc:
    case SourceError::BadValue:
      count(kind == SourceError::BadCrc ? fp::DecodeError::BadCrc : fp::DecodeError::BadValue);
      s.status.check_failed = true;
      s.ok_in_row = 0;
      break;
    case SourceError::StaleCounter: count(fp::DecodeError::RepeatedCounter); break;
    case SourceError::Timeout: s.status.timeouts++; break;
    case SourceError::Exception: s.status.exceptions++; break;
    case SourceError::LinkCrc: count(fp::DecodeError::BadCrc); break;
  }
}

void PanelMapper::on_connection(std::size_t source, bool connected, int64_t now_us, std::string_view down_reason) {
  if (source >= sources_.size()) return;
  SourceState& s = sources_[source];
  if (connected) s.status.down_reason.clear();
  else if (!down_reason.empty() && s.status.down_reason != down_reason) s.status.down_reason = down_reason;
  if (s.status.connected == connected) return;
  s.status.ever_connected = s.status.ever_connected || connected;
  if (connected && s.last_any_valid_us != 0) s.status.reconnects++;
  s.status.connected = connected;
  // A transport opened afresh (interface up again) starts error-active.
  if (connected) s.status.bus_state = io::CanBusState::Active;
  if (!connected) {
    for (auto& b : s.bindings) b.last_us = 0;
    s.hid_last_us = 0;
    s.poll_last_us = 0;
    s.decoder.reset();
    s.last_valid_us.fill(0);
    s.status.heartbeat_seen = false;
    s.heartbeat_us = 0;
    s.nmt_state = fp::canopen::NmtState::BootUp;
    s.axes_seen[0] = s.axes_seen[1] = false;
    s.buttons_seen = s.switches_seen = false;
  }
  (void)now_us;
}

std::optional<PanelMapper::SourceTrouble> PanelMapper::source_trouble(const SourceState& s, int64_t now_us) const {
  using msgs::FailsafeCause;
  const auto& def = definition_.sources[static_cast<std::size_t>(&s - sources_.data())];
  const auto trouble = [&def](FailsafeCause cause, const std::string& what) {
    return SourceTrouble{cause, def.name + ": " + what};
  };
  const auto stale = [&](const std::string& what, int64_t age_us) {
    return trouble(FailsafeCause::SourceStale, "stale (no " + what + " for " + std::to_string(age_us / 1000) + " ms)");
  };
  if (!s.status.connected) return trouble(FailsafeCause::SourceDown, "disconnected");
  if (s.status.bus_state == io::CanBusState::BusOff) return trouble(FailsafeCause::SourceError, "CAN bus-off");
  const int64_t timeout_us = 1000 * static_cast<int64_t>(def.timeout_ms);
  if (def.is_hid()) {
    // A HID device has no heartbeat: the first report after opening proves
    // it talks; timeout_ms 0 trusts it until it is unplugged.
    if (!s.hid && s.named == 0) {
      if (!s.hid_error.empty()) return SourceTrouble{FailsafeCause::SourceError, s.hid_error};
      return trouble(FailsafeCause::SourceStale, "no report descriptor yet");
    }
    if (s.hid_last_us == 0) return trouble(FailsafeCause::SourceStale, "no report yet");
    const int64_t age_us = now_us - s.hid_last_us;
    if (timeout_us > 0 && age_us > timeout_us) return stale("report", age_us);
    return std::nullopt;
  }
  if (def.is_generic_modbus()) {
    // A third-party device has no alive counter or CRC of ours: it is
    // trusted while its polls are answered.
    if (s.poll_last_us == 0) return trouble(FailsafeCause::SourceStale, "no poll answered yet");
    const int64_t age_us = now_us - s.poll_last_us;
    if (age_us > timeout_us) return stale("poll answered", age_us);
    return std::nullopt;
  }
  if (def.is_canopen()) return canopen_trouble(s, def, now_us);
  if (def.is_dbc()) {
    // A DBC device has no heartbeat or status of ours: every bound message
    // must keep arriving, and its frames must fit the DBC.
    for (const auto& b : s.bindings) {
      if (b.last_us == 0) return trouble(FailsafeCause::SourceStale, "no " + b.message->name + " frame yet");
      const int64_t age_us = now_us - b.last_us;
      // A J1939 console sends slow PGNs (a BAM takes 50 ms a packet) at
      // their own cycle: three GenMsgCycleTimes of it, if longer.
      const int64_t limit_us =
          def.is_j1939() ? std::max<int64_t>(timeout_us, 3000 * int64_t{b.message->cycle_time_ms}) : timeout_us;
      if (age_us > limit_us) return stale(b.message->name + " frame", age_us);
    }
    if (s.status.check_failed) return trouble(FailsafeCause::SourceError, "frames do not fit the DBC");
    return std::nullopt;
  }
  for (std::size_t t = 0; t < fp::kFrameTypeCount; ++t) {
    if (!s.needs_type[t]) continue;
    // The type's name only on the way out: this runs at every evaluation.
    const auto type = [t] { return std::string(fp::to_string(static_cast<fp::FrameType>(t))); };
    if (s.last_valid_us[t] == 0) return trouble(FailsafeCause::SourceStale, "no " + type() + " frame yet");
    const int64_t age_us = now_us - s.last_valid_us[t];
    if (age_us > timeout_us) return stale("valid " + type() + " frame", age_us);
  }
  if (!s.status.heartbeat_seen) return trouble(FailsafeCause::SourceStale, "no heartbeat yet");
  if (now_us - s.last_valid_us[type_index(fp::FrameType::Heartbeat)] > heartbeat_timeout_us(def))
    return trouble(FailsafeCause::SourceStale, "heartbeat stale");
  if (s.protocol_version != fp::kProtocolVersion)
    return trouble(FailsafeCause::SourceError, "console speaks protocol version " + std::to_string(s.protocol_version) +
                                                   ", expected " + std::to_string(fp::kProtocolVersion));
  if (s.status.console_status != fp::PanelStatus::Operational)
    return trouble(FailsafeCause::SourceError, "console status " + std::string(fp::to_string(s.status.console_status)));
  if (s.status.check_failed) return trouble(FailsafeCause::ProtectionFailed, "protection check failed");
  return std::nullopt;
}

// A CANopen node is trusted while its heartbeat comes within the consumer
// time (timeout_ms) and says Operational, and each bound object came in a
// PDO since it entered Operational; a cyclic PDO (every n-th SYNC, or an
// event timer) must also keep coming: within three of its periods.
std::optional<PanelMapper::SourceTrouble> PanelMapper::canopen_trouble(const SourceState& s,
                                                                      const panels::SourceDefinition& def,
                                                                      int64_t now_us) const {
  namespace co = fp::canopen;
  // The text only on the way out: this runs at every evaluation.
  const auto trouble = [&def](msgs::FailsafeCause cause, const std::string& what) {
    return SourceTrouble{cause, def.name + ": node " + std::to_string(def.node) + what};
  };
  if (!s.status.heartbeat_seen) return trouble(msgs::FailsafeCause::SourceStale, ": no heartbeat yet");
  const int64_t heartbeat_age_us = now_us - s.heartbeat_us;
  if (heartbeat_age_us > 1000 * static_cast<int64_t>(def.timeout_ms))
    return trouble(msgs::FailsafeCause::SourceStale,
                   ": stale (no heartbeat for " + std::to_string(heartbeat_age_us / 1000) + " ms)");
  if (s.nmt_state != co::NmtState::Operational)
    return trouble(msgs::FailsafeCause::SourceError, " " + std::string(co::to_string(s.nmt_state)));
  const auto& messages = def.eds->tpdo_messages();
  for (const auto& b : s.bindings) {
    if (b.last_us == 0)
      return trouble(msgs::FailsafeCause::SourceStale, ": no " + b.message->name + " since operational");
    const fp::canopen::Pdo& pdo = def.eds->tpdos()[static_cast<std::size_t>(b.message - messages.data())];
    int64_t period_us = 1000 * static_cast<int64_t>(pdo.event_timer_ms);
    if (co::is_cyclic_sync(pdo.transmission_type))
      period_us = static_cast<int64_t>(def.sync_period_us) * pdo.transmission_type;
    const int64_t age_us = now_us - b.last_us;
    if (period_us > 0 && age_us > 3 * period_us)
      return trouble(msgs::FailsafeCause::SourceStale,
                     ": stale (no " + b.message->name + " for " + std::to_string(age_us / 1000) + " ms)");
  }
  if (s.status.check_failed) return trouble(msgs::FailsafeCause::SourceError, ": PDOs shorter than their mapping");
  return std::nullopt;
}

// The causes and the reasons of one evaluation, in the order they were found.
struct PanelMapper::Failsafe {
  msgs::FailsafeCauses causes;
  std::string reasons;  // "; "-joined

  void add(msgs::FailsafeCause cause, const std::string& reason) {
    causes.add(cause);
    if (!reasons.empty()) reasons += "; ";
    reasons += reason;
  }
};

std::vector<bool> PanelMapper::evaluate_sources(int64_t now_us, PanelSnapshot& snap, Failsafe& why) const {
  std::vector<bool> healthy(sources_.size());
  for (std::size_t i = 0; i < sources_.size(); ++i) {
    const SourceState& s = sources_[i];
    const std::optional<SourceTrouble> trouble = source_trouble(s, now_us);
    healthy[i] = !trouble;
    if (trouble) why.add(trouble->cause, trouble->reason);
    SourceStatus status = s.status;
    status.stale = trouble && (!s.status.connected || s.last_any_valid_us == 0 ||
                               trouble->cause == msgs::FailsafeCause::SourceStale);
    status.last_frame_age_us = s.last_any_valid_us == 0 ? -1 : now_us - s.last_any_valid_us;
    snap.sources.push_back(std::move(status));
  }
  return healthy;
}

void PanelMapper::map_axis(std::size_t i, const SourceState& s, int64_t now_us, ControlValue& v, Failsafe& why) const {
  const auto& c = definition_.controls[i];
  float unit = 0.0f;
  if (const int b = binding_of_control_[i]; b >= 0) {
    // A DBC signal's physical range [min, max] maps linearly to -1..1.
    const double value = s.bindings[static_cast<std::size_t>(b)].value;
    unit = static_cast<float>(2.0 * (value - c.range_min) / (c.range_max - c.range_min) - 1.0);
  } else {
    const int16_t raw = s.axes[c.signal.index];
    if (raw == fp::kAxisInvalid) {
      set_safe(c, v);
      why.add(msgs::FailsafeCause::ControlInvalid, c.name + ": not available");
      return;
    }
    unit = fp::axis_to_unit(raw);
  }
  if (!input_faults_.empty()) {
    const FaultEffect effect = apply_axis_faults(input_faults_, i, now_us, unit);
    if (effect == FaultEffect::Lost || effect == FaultEffect::OutOfRange) {
      set_safe(c, v);
      why.add(msgs::FailsafeCause::InputFault, c.name + (effect == FaultEffect::Lost ? ": disconnected (fault)"
                                                                                     : ": out of range (fault)"));
      return;
    }
  }
  const AxisShaping shaping{c.deadband, c.expo, c.scale, c.invert};
  const float x = shape_axis(unit, shaping);
  ControlFilter& f = filters_[i];
  // Restart from the safe value: after a dead-man press the axis ramps up, never jumps.
  if (f.was_safe) f.lowpass.reset(c.safe_axis, now_us);
  v.axis = f.lowpass.update(x, now_us);
}

void PanelMapper::map_button(std::size_t i, const SourceState& s, int64_t now_us, ControlValue& v, Failsafe& why) const {
  const auto& c = definition_.controls[i];
  const int b = binding_of_control_[i];
  bool raw = b >= 0 ? s.bindings[static_cast<std::size_t>(b)].value != 0.0 : ((s.buttons >> c.signal.index) & 1u) != 0;
  if (!input_faults_.empty() && apply_button_faults(input_faults_, i, now_us, raw) == FaultEffect::Lost) {
    set_safe(c, v);
    why.add(msgs::FailsafeCause::InputFault, c.name + ": disconnected (fault)");
    return;
  }
  ControlFilter& f = filters_[i];
  // After a loss the button restarts "not activated": a latched
  // toggle never survives the source going away.
  if (f.was_safe) f.button.reset(raw, c.behaviour == panels::ButtonBehaviour::Direct && raw, now_us);
  v.pressed = f.button.update(raw, now_us);
}

void PanelMapper::map_bits_switch(std::size_t i, const SourceState& s, int64_t now_us, ControlValue& v,
                                  Failsafe& why) const {
  const auto& c = definition_.controls[i];
  // Between the detents of a rotary switch no contact (or two) may
  // be closed for a moment: keep the last valid position.
  ControlFilter& f = filters_[i];
  const auto p = switch_from_bits(s.buttons, c.bits,
                                  c.encoding == panels::BitsEncoding::OneHot ? BitsEncoding::OneHot
                                                                             : BitsEncoding::Binary,
                                  c.positions.size());
  if (p) f.last_position = p;
  if (!f.last_position) {
    set_safe(c, v);
    why.add(msgs::FailsafeCause::ControlInvalid, c.name + ": position not available");
    return;
  }
  uint8_t position = *f.last_position;
  if (!input_faults_.empty()) {
    const FaultEffect effect = apply_switch_faults(input_faults_, i, now_us, position);
    if (effect == FaultEffect::Lost || effect == FaultEffect::OutOfRange || position >= c.positions.size()) {
      set_safe(c, v);
      why.add(msgs::FailsafeCause::InputFault, c.name + (effect == FaultEffect::Lost ? ": disconnected (fault)"
                                                                                     : ": out of range (fault)"));
      return;
    }
  }
  v.position = position;
}

void PanelMapper::map_switch(std::size_t i, const SourceState& s, int64_t now_us, ControlValue& v, Failsafe& why) const {
  const auto& c = definition_.controls[i];
  if (!c.bits.empty()) return map_bits_switch(i, s, now_us, v, why);
  uint8_t position = s.switches[c.signal.index];
  if (const int b = binding_of_control_[i]; b >= 0) {
    // A DBC signal's value is the position index (its VAL_ table names them).
    const double value = s.bindings[static_cast<std::size_t>(b)].value;
    position = value >= 0.0 && value < 255.0 ? static_cast<uint8_t>(std::lround(value)) : fp::kSwitchInvalid;
    if (c.modbus_point && position >= c.positions.size()) {
      // A register's number: no "not available" value.
      set_safe(c, v);
      why.add(msgs::FailsafeCause::ControlInvalid,
              c.name + ": position " + std::to_string(std::lround(value)) + " unknown");
      return;
    }
  }
  if (!input_faults_.empty() && apply_switch_faults(input_faults_, i, now_us, position) == FaultEffect::Lost) {
    set_safe(c, v);
    why.add(msgs::FailsafeCause::InputFault, c.name + ": disconnected (fault)");
    return;
  }
  if (position >= c.positions.size()) {
    set_safe(c, v);
    why.add(msgs::FailsafeCause::ControlInvalid,
            c.name + ": position " +
                (position == fp::kSwitchInvalid ? std::string("not available") : std::to_string(position) + " unknown"));
    return;
  }
  v.position = position;
}

PanelSnapshot PanelMapper::evaluate(int64_t now_us) const {
  PanelSnapshot snap;
  snap.time_us = now_us;
  snap.controls.resize(definition_.controls.size());
  snap.sources.reserve(sources_.size());

  Failsafe why;
  const std::vector<bool> healthy = evaluate_sources(now_us, snap, why);
  bool estop = false;
  std::optional<std::size_t> deadman_index;
  for (std::size_t i = 0; i < definition_.controls.size(); ++i) {
    const auto& c = definition_.controls[i];
    ControlValue& v = snap.controls[i];
    if (!healthy[c.source]) {
      set_safe(c, v);
    } else {
      const SourceState& s = sources_[c.source];
      switch (c.kind) {
        case ControlKind::Axis: map_axis(i, s, now_us, v, why); break;
        case ControlKind::Button: map_button(i, s, now_us, v, why); break;
        case ControlKind::Switch: map_switch(i, s, now_us, v, why); break;
      }
    }
    // A forced-safe e-stop reads "pressed" but nobody pressed it: the
    // source's own reason says why.
    if (c.role == ControlRole::Estop && v.pressed && !v.forced_safe) estop = true;
    if (c.role == ControlRole::Deadman) deadman_index = i;
  }
  if (estop) why.add(msgs::FailsafeCause::Estop, "e-stop pressed");

  for (const InputFault& f : input_faults_)
    if (f.active(now_us))
      snap.active_faults.push_back(f.id + ": " + to_string(f.kind) + " " + definition_.controls[f.control].name);
  snap.failsafe = why.causes.any();
  snap.failsafe_causes = why.causes;
  snap.failsafe_reason = std::move(why.reasons);
  snap.deadman = deadman_index && snap.controls[*deadman_index].pressed;

  // Motion needs the dead-man held and no e-stop; a panel in failsafe for any
  // reason stops motion too, so one stale source cannot leave another's stick live.
  if (!snap.deadman || snap.failsafe)
    for (std::size_t i = 0; i < definition_.controls.size(); ++i)
      if (definition_.controls[i].motion) set_safe(definition_.controls[i], snap.controls[i]);
  for (std::size_t i = 0; i < definition_.controls.size(); ++i) {
    filters_[i].was_safe = snap.controls[i].forced_safe;
    if (snap.controls[i].forced_safe && !healthy[definition_.controls[i].source]) filters_[i].last_position.reset();
  }
  return snap;
}

PanelSnapshot PanelMapper::preview(int64_t now_us) const {
  const std::vector<ControlFilter> saved = filters_;
  PanelSnapshot snap = evaluate(now_us);
  filters_ = saved;
  return snap;
}

std::string PanelMapper::inject_input_fault(InputFault fault) {
  if (fault.control >= definition_.controls.size()) return "no control #" + std::to_string(fault.control);
  const auto& c = definition_.controls[fault.control];
  const bool any = fault.kind == InputFaultKind::StuckAt || fault.kind == InputFaultKind::Intermittent ||
                   fault.kind == InputFaultKind::Disconnect;
  const bool ok = c.kind == ControlKind::Axis ||
                  any || (c.kind == ControlKind::Switch && fault.kind == InputFaultKind::OutOfRange);
  if (!ok) return std::string(to_string(fault.kind)) + " does not apply to " + c.name + " (not an axis)";
  // The same id replaces; those that ended before this one starts go.
  std::erase_if(input_faults_, [&](const InputFault& f) {
    return f.id == fault.id || (f.end_us != 0 && f.end_us <= fault.start_us);
  });
  input_faults_.push_back(std::move(fault));
  return {};
}

std::size_t PanelMapper::clear_input_faults(const std::string& id, int64_t now_us) {
  const std::size_t named = std::erase_if(input_faults_, [&](const InputFault& f) { return id.empty() || f.id == id; });
  std::erase_if(input_faults_, [&](const InputFault& f) { return f.end_us != 0 && f.end_us <= now_us; });
  return named;
}

}  // namespace rise::hil
