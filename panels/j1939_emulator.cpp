#include "panels/j1939_emulator.hpp"

#include <algorithm>
#include <stdexcept>

namespace rise::panels {
namespace {
namespace fp = rise::firmware_protocol;
namespace j1939 = rise::firmware_protocol::j1939;

constexpr uint64_t kDefaultConsoleName = 0x00A0000000C0FFEEull;
constexpr uint8_t kDefaultConsoleAddress = 0x21;

uint64_t console_name(const SourceDefinition& s, const J1939EmulatorSettings& settings) {
  if (settings.name != 0) return settings.name;
  return s.console_name ? *s.console_name : kDefaultConsoleName;
}

uint8_t console_address(const SourceDefinition& s, const J1939EmulatorSettings& settings) {
  if (settings.address != j1939::kNullAddress) return settings.address;
  return s.console_address != j1939::kNullAddress ? s.console_address : kDefaultConsoleAddress;
}

// The physical value the firmware sends for a control at rest.
double rest_value(const ControlDefinition& c) {
  return c.kind == ControlKind::Axis ? (c.range_min + c.range_max) / 2.0 : 0.0;
}

}  // namespace

J1939Emulator::J1939Emulator(const PanelDefinition& definition, std::size_t source, J1939EmulatorSettings settings)
    : definition_(definition),
      source_(source),
      settings_(settings),
      claimer_(console_name(definition.sources.at(source), settings),
               console_address(definition.sources.at(source), settings)) {
  if (!definition.sources[source].is_j1939())
    throw std::runtime_error("source '" + definition.sources[source].name + "' does not speak j1939");
  for (std::size_t i = 0; i < definition.controls.size(); ++i) {
    const ControlDefinition& c = definition.controls[i];
    if (c.source != source || !c.dbc_message) continue;
    auto it = std::find_if(messages_.begin(), messages_.end(), [&](const Message& m) { return m.dbc == c.dbc_message; });
    if (it == messages_.end()) {
      Message m;
      m.dbc = c.dbc_message;
      if (m.dbc->cycle_time_ms > 0) m.period_us = 1000 * int64_t{m.dbc->cycle_time_ms};
      messages_.push_back(m);
      it = messages_.end() - 1;
    }
    it->controls.push_back(i);
  }
  rest();
}

void J1939Emulator::rest() {
  values_.assign(definition_.controls.size(), 0.0);
  for (std::size_t i = 0; i < values_.size(); ++i) values_[i] = rest_value(definition_.controls[i]);
}

void J1939Emulator::restart() {
  rest();
  silent_ = ended_ = false;
}

void J1939Emulator::apply(const TimelineEvent& e) {
  using K = TimelineEvent::Kind;
  switch (e.kind) {
    case K::Set: {
      const ControlDefinition& c = definition_.controls[e.control];
      if (c.kind == ControlKind::Axis)
        values_[e.control] = c.range_min + (static_cast<double>(e.axis) + 1.0) / 2.0 * (c.range_max - c.range_min);
      else if (c.kind == ControlKind::Button)
        values_[e.control] = e.pressed ? 1.0 : 0.0;
      else
        values_[e.control] = e.position;
      break;
    }
    case K::Silent: silent_ = true; break;
    case K::Resume: silent_ = false; break;
    case K::End: ended_ = true; break;
    case K::Status:
    case K::Corrupt:
    case K::Invalid: break;  // rise-can-v1's status and protection: J1939 has neither
  }
}

bool J1939Emulator::send(hil::io::CanBus& bus, const j1939::Frame& frame) {
  hil::io::CanFrame f;
  f.id = j1939::encode_id(frame.id);
  f.extended = true;
  f.len = frame.len;
  std::copy_n(frame.data.begin(), frame.len, f.data.begin());
  const bool ok = bus.send(f) == hil::io::IoStatus::Ok;
  frames_sent_ += ok ? 1 : 0;
  return ok;
}

std::vector<uint8_t> J1939Emulator::encode(const Message& m) const {
  std::vector<fp::SignalValue> values;
  for (std::size_t i : m.controls) values.push_back({definition_.controls[i].dbc_signal->name, values_[i]});
  return definition_.sources[source_].dbc->encode(*m.dbc, values);
}

int J1939Emulator::send_message(hil::io::CanBus& bus, Message& m, int64_t now_us) {
  // Keeps its cadence; after a pause (silent) it starts again from now.
  m.next_us = m.next_us + m.period_us > now_us ? m.next_us + m.period_us : now_us + m.period_us;
  std::vector<uint8_t> data;
  try {
    data = encode(m);
  } catch (const std::exception&) {
    return 0;  // a value the DBC cannot carry: the console sends nothing (stale at the bridge)
  }
  const j1939::Id id = j1939::decode_id(m.dbc->id);
  if (data.size() <= 8) {
    j1939::Frame f;
    f.id = {id.priority, id.pgn, claimer_.address(), id.da};
    f.len = static_cast<uint8_t>(data.size());
    std::copy(data.begin(), data.end(), f.data.begin());
    return send(bus, f) ? 1 : 0;
  }
  if (bam_.busy()) return 0;  // one BAM at a time from one address (J1939-21 5.10.3)
  bam_.start(id.pgn, claimer_.address(), data, id.priority);
  bam_next_us_ = now_us;
  return 0;
}

int J1939Emulator::tick(hil::io::CanBus& bus, int64_t now_us) {
  const int64_t now_ms = now_us / 1000;
  if (!claimed_once_) {
    claimed_once_ = true;
    return send(bus, claimer_.start(now_ms)) ? 1 : 0;
  }
  claimer_.tick(now_ms);
  if (claimer_.address() == j1939::kNullAddress || silent_ || ended_) return 0;
  int sent = 0;
  for (Message& m : messages_)
    if (now_us >= m.next_us) sent += send_message(bus, m, now_us);
  if (bam_.busy() && now_us >= bam_next_us_) {
    if (auto f = bam_.next()) sent += send(bus, *f) ? 1 : 0;
    bam_next_us_ = now_us + settings_.bam_packet_gap_us;
  }
  return sent;
}

void J1939Emulator::on_frame(hil::io::CanBus& bus, const hil::io::CanFrame& frame, int64_t now_us) {
  if (!frame.extended || frame.remote || frame.error || frame.len > 8) return;
  j1939::Frame f;
  f.id = j1939::decode_id(frame.id);
  f.len = frame.len;
  std::copy_n(frame.data.begin(), frame.len, f.data.begin());
  j1939::Frame reply;
  if (claimer_.on_frame(f, now_us / 1000, reply)) send(bus, reply);
}

}  // namespace rise::panels
