#include "panels/canopen_emulator.hpp"

#include <cmath>
#include <cstring>
#include <sstream>

#include "firmware_protocol/canopen_eds.hpp"
#include "firmware_protocol/console_can.hpp"
#include "firmware_protocol/dbc.hpp"

namespace rise::panels {
namespace {
namespace fp = rise::firmware_protocol;
namespace co = rise::firmware_protocol::canopen;

// An axis' -1..1 as the object's raw value: the inverse of the bridge's
// range mapping (range_min..range_max ↔ -1..1).
int64_t axis_raw(const ControlDefinition& c, float unit) {
  const double value = c.range_min + (static_cast<double>(unit) + 1.0) / 2.0 * (c.range_max - c.range_min);
  if (c.dbc_signal->value_type == fp::SignalValueType::Float32) {
    const auto f = static_cast<float>(value);
    uint32_t bits = 0;
    std::memcpy(&bits, &f, sizeof bits);
    return bits;
  }
  if (c.dbc_signal->value_type == fp::SignalValueType::Float64) {
    int64_t bits = 0;
    std::memcpy(&bits, &value, sizeof bits);
    return bits;
  }
  return std::llround(value);
}

template <class T>
std::size_t position(const std::vector<T>& items, const T* item) {
  return static_cast<std::size_t>(item - items.data());
}
}  // namespace

CanopenEmulator::CanopenEmulator(const PanelDefinition& definition, std::size_t source)
    : definition_(definition), source_(source), def_(definition.sources.at(source)) {
  for (const fp::DbcMessage& m : def_.eds->tpdo_messages()) tpdos_.push_back({std::vector<int64_t>(m.signals.size()), true, -1, 0});
  power_up_inputs();
}

void CanopenEmulator::power_up_inputs() {
  for (TpdoState& t : tpdos_) {
    std::fill(t.raw.begin(), t.raw.end(), 0);
    t.changed = true;
  }
  // Switches rest where their safe position is at power-up; sticks centred.
  for (const ControlDefinition& c : definition_.controls) {
    if (c.source != source_) continue;
    TimelineEvent rest;
    rest.axis = 0.0f;
    rest.position = c.safe_switch;
    set_control(c, rest);
  }
}

void CanopenEmulator::restart() {
  power_up_inputs();
  if (!powered_) boot_due_ = true;
  powered_ = true;
  ended_ = false;
  corrupt_left_ = 0;
}

void CanopenEmulator::set_control(const ControlDefinition& c, const TimelineEvent& e) {
  const auto& messages = def_.eds->tpdo_messages();
  TpdoState& t = tpdos_[position(messages, c.dbc_message)];
  const std::size_t signal = position(c.dbc_message->signals, c.dbc_signal);
  const int64_t raw = c.kind == ControlKind::Axis     ? axis_raw(c, e.axis)
                      : c.kind == ControlKind::Button ? (e.pressed ? 1 : 0)
                                                      : e.position;
  t.changed = t.changed || t.raw[signal] != raw;
  t.raw[signal] = raw;
}

void CanopenEmulator::apply(const TimelineEvent& e) {
  using K = TimelineEvent::Kind;
  switch (e.kind) {
    case K::Set: {
      const ControlDefinition& c = definition_.controls.at(e.control);
      if (c.source == source_) set_control(c, e);
      break;
    }
    case K::Silent:
      powered_ = false;
      state_ = co::NmtState::BootUp;
      break;
    case K::Resume:
      if (!powered_) boot_due_ = true;
      powered_ = true;
      break;
    case K::Status:
      switch (static_cast<fp::PanelStatus>(e.status)) {
        case fp::PanelStatus::Operational: enter(co::NmtState::Operational); break;
        case fp::PanelStatus::Shutdown: enter(co::NmtState::Stopped); break;
        case fp::PanelStatus::Init:
        case fp::PanelStatus::Fault: enter(co::NmtState::PreOperational); break;
      }
      break;
    case K::Corrupt: corrupt_left_ += e.count; break;
    case K::Invalid: break;  // an object has no "not available" value
    case K::End: ended_ = true; break;
  }
}

void CanopenEmulator::enter(co::NmtState state) {
  // A new state is told at once, not at the next period (as CANopenNode's
  // heartbeat producer does).
  if (state != state_) next_heartbeat_us_ = 0;
  // Entering Operational sends every TPDO once (CANopen devices commonly do;
  // the master needs the start-up state of event-driven objects).
  if (state == co::NmtState::Operational && state_ != co::NmtState::Operational)
    for (TpdoState& t : tpdos_) {
      t.changed = true;
      t.syncs = 0;
      t.last_sent_us = -1;
    }
  state_ = state;
}

void CanopenEmulator::boot(int64_t now_us) {
  state_ = co::NmtState::BootUp;
  boot_due_ = false;
  next_heartbeat_us_ = now_us + 1000 * static_cast<int64_t>(def_.eds->heartbeat_ms());
}

bool CanopenEmulator::send(hil::io::CanBus& bus, const co::Frame& frame) {
  hil::io::CanFrame f;
  f.id = frame.cob_id;
  f.extended = frame.extended;
  f.len = frame.len;
  std::copy(frame.data.begin(), frame.data.end(), f.data.begin());
  if (bus.send(f) != hil::io::IoStatus::Ok) return false;
  ++frames_sent_;
  return true;
}

bool CanopenEmulator::send_tpdo(hil::io::CanBus& bus, std::size_t pdo, int64_t now_us) {
  const fp::DbcMessage& m = def_.eds->tpdo_messages()[pdo];
  TpdoState& t = tpdos_[pdo];
  co::Frame frame;
  frame.cob_id = m.id;
  frame.extended = m.extended;
  frame.len = std::min<uint8_t>(m.dlc, 8);
  for (std::size_t i = 0; i < m.signals.size(); ++i)
    fp::insert_raw(m.signals[i], static_cast<uint64_t>(t.raw[i]), std::span<uint8_t>(frame.data.data(), frame.len));
  if (corrupt_left_ > 0 && frame.len > 0) {
    --frame.len;  // one byte short of the mapping: a length error (CiA 301 EMCY 0x8210)
    --corrupt_left_;
  }
  t.changed = false;
  t.last_sent_us = now_us;
  return send(bus, frame);
}

int CanopenEmulator::tick(hil::io::CanBus& bus, int64_t now_us) {
  if (ended_ || !powered_) return 0;
  int sent = 0;
  if (boot_due_) {
    boot(now_us);
    // The boot-up message: a heartbeat with state 0 (CiA 301 §7.2.8.3.3).
    const int beat = send(bus, co::heartbeat_frame(def_.node, co::NmtState::BootUp)) ? 1 : 0;
    sent += beat, heartbeats_sent_ += beat;
    state_ = co::NmtState::PreOperational;  // after the boot-up, on its own (§7.3.2.2.1)
  }
  if (now_us >= next_heartbeat_us_) {
    const int beat = send(bus, co::heartbeat_frame(def_.node, state_)) ? 1 : 0;
    sent += beat, heartbeats_sent_ += beat;
    const int64_t period_us = 1000 * static_cast<int64_t>(def_.eds->heartbeat_ms());
    next_heartbeat_us_ += period_us;
    if (next_heartbeat_us_ <= now_us) next_heartbeat_us_ = now_us + period_us;
  }
  if (state_ != co::NmtState::Operational) return sent;
  const auto& pdos = def_.eds->tpdos();
  for (std::size_t p = 0; p < pdos.size(); ++p) {
    if (co::is_synchronous(pdos[p].transmission_type) || pdos[p].transmission_type < 0xFE) continue;
    const TpdoState& t = tpdos_[p];
    const int64_t since_us = t.last_sent_us < 0 ? INT64_MAX : now_us - t.last_sent_us;
    const bool on_change = t.changed && since_us >= 100 * static_cast<int64_t>(pdos[p].inhibit_100us);
    const bool on_timer = pdos[p].event_timer_ms > 0 && since_us >= 1000 * static_cast<int64_t>(pdos[p].event_timer_ms);
    if (on_change || on_timer) sent += send_tpdo(bus, p, now_us);
  }
  return sent;
}

void CanopenEmulator::on_sync(hil::io::CanBus& bus, int64_t now_us) {
  ++syncs_seen_;
  if (state_ != co::NmtState::Operational) return;
  const auto& pdos = def_.eds->tpdos();
  for (std::size_t p = 0; p < pdos.size(); ++p) {
    const uint8_t type = pdos[p].transmission_type;
    if (!co::is_synchronous(type)) continue;
    TpdoState& t = tpdos_[p];
    if (type == 0 ? t.changed : ++t.syncs >= type) {
      t.syncs = 0;
      send_tpdo(bus, p, now_us);
    }
  }
}

bool CanopenEmulator::on_rpdo(const hil::io::CanFrame& frame) {
  const auto& messages = def_.eds->rpdo_messages();
  for (const fp::DbcMessage& m : messages) {
    if (m.id != frame.id || m.extended != frame.extended || frame.len < m.dlc) continue;
    const std::span<const uint8_t> data(frame.data.data(), frame.len);
    bool changed = false;
    const auto show = [&](const std::string& name, double value) {
      const auto it = feedback_.find(name);
      changed = changed || it == feedback_.end() || it->second != value;
      feedback_[name] = value;
    };
    for (const LedDefinition& led : definition_.leds)
      if (led.source == source_ && led.pdo_message == &m) show(led.name, fp::extract_raw(*led.pdo_signal, data) != 0);
    for (const DisplayDefinition& d : definition_.displays)
      if (d.source == source_ && d.pdo_message == &m)
        show(d.name, static_cast<double>(fp::extract_raw(*d.pdo_signal, data)) / std::pow(10.0, d.decimals));
    return changed;
  }
  return false;
}

bool CanopenEmulator::on_frame(hil::io::CanBus& bus, const hil::io::CanFrame& frame, int64_t now_us) {
  if (ended_ || !powered_ || frame.error || frame.remote || frame.fd) return false;
  const std::span<const uint8_t> data(frame.data.data(), frame.len);
  const co::NmtRequest nmt = frame.extended ? co::NmtRequest{} : co::read_nmt(frame.id, data);
  if (nmt.addresses(def_.node)) {
    const co::NmtState next = co::next_state(state_, nmt.command);
    if (next == co::NmtState::BootUp) boot_due_ = true;  // reset: boots again at the next tick
    else enter(next);
    return false;
  }
  if (!frame.extended && frame.id == co::kSyncCobId && frame.len <= 1) {
    on_sync(bus, now_us);
    return false;
  }
  return on_rpdo(frame);
}

std::optional<double> CanopenEmulator::feedback(const std::string& name) const {
  const auto it = feedback_.find(name);
  if (it == feedback_.end()) return std::nullopt;
  return it->second;
}

std::string CanopenEmulator::feedback_text() const {
  std::ostringstream out;
  out << "leds";
  for (const LedDefinition& led : definition_.leds) {
    if (led.source != source_) continue;
    const auto v = feedback(led.name);
    out << ' ' << led.name << '=' << (!v ? "-" : *v != 0 ? "on" : "off");
  }
  for (const DisplayDefinition& d : definition_.displays) {
    if (d.source != source_) continue;
    const auto v = feedback(d.name);
    out << "; display " << d.name << '=';
    if (!v) out << '-';
    else {
      out.precision(d.decimals);
      out << std::fixed << *v;
    }
  }
  return out.str();
}

int64_t CanopenEmulator::object_raw(uint16_t index, uint8_t subindex) const {
  const co::OdEntry* entry = def_.eds->find(index, subindex);
  if (!entry) return 0;
  const co::PdoSignal pdo = def_.eds->pdo_signal(*entry, true);
  if (!pdo.signal) return 0;
  return tpdos_[position(def_.eds->tpdo_messages(), pdo.message)].raw[position(pdo.message->signals, pdo.signal)];
}

}  // namespace rise::panels
