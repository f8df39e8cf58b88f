#include "panels/console_emulator.hpp"

#include <sstream>

namespace rise::panels {
namespace {
namespace fp = rise::firmware_protocol;

int64_t period_us(fp::FrameType t) { return 1000 * static_cast<int64_t>(fp::nominal_period_ms(t)); }

const char* buzzer_text(fp::BuzzerMode m) {
  switch (m) {
    case fp::BuzzerMode::Off: return "off";
    case fp::BuzzerMode::On: return "on";
    case fp::BuzzerMode::Beep: return "beep";
  }
  return "?";
}
}  // namespace

bool ConsoleFeedback::operator==(const ConsoleFeedback& o) const {
  if (leds_on != o.leds_on || buzzer != o.buzzer || displays.size() != o.displays.size()) return false;
  for (const auto& [index, d] : displays) {
    const auto it = o.displays.find(index);
    if (it == o.displays.end() || it->second.raw != d.raw || it->second.decimals != d.decimals) return false;
  }
  return true;
}

ConsoleEmulator::ConsoleEmulator(const PanelDefinition& definition, std::size_t source)
    : definition_(definition),
      source_(source),
      encoder_(definition.sources.at(source).node),
      feedback_decoder_(definition.sources.at(source).node) {
  power_up_inputs();
}

void ConsoleEmulator::power_up_inputs() {
  axes_.fill(0);
  buttons_ = 0;
  switches_.fill(0);
  // At power-up the firmware reads each switch where it rests; a scripted
  // session starts with switches in their safe position unless told otherwise.
  for (const auto& c : definition_.controls)
    if (c.source == source_ && c.kind == ControlKind::Switch) switches_[c.signal.index] = c.safe_switch;
  digital_changed_ = true;
}

void ConsoleEmulator::restart() {
  power_up_inputs();
  status_ = fp::PanelStatus::Operational;
  silent_ = false;
  ended_ = false;
  corrupt_left_ = 0;
}

void ConsoleEmulator::apply(const TimelineEvent& e) {
  using K = TimelineEvent::Kind;
  switch (e.kind) {
    case K::Set: {
      const ControlDefinition& c = definition_.controls.at(e.control);
      if (c.source != source_) return;
      switch (c.kind) {
        case ControlKind::Axis: axes_[c.signal.index] = fp::axis_from_unit(e.axis); break;
        case ControlKind::Button:
          buttons_ = e.pressed ? buttons_ | (1u << c.signal.index) : buttons_ & ~(1u << c.signal.index);
          digital_changed_ = true;
          break;
        case ControlKind::Switch:
          switches_[c.signal.index] = e.position;
          digital_changed_ = true;
          break;
      }
      break;
    }
    case K::Invalid: {
      const ControlDefinition& c = definition_.controls.at(e.control);
      if (c.source != source_) return;
      if (c.kind == ControlKind::Axis) axes_[c.signal.index] = fp::kAxisInvalid;
      if (c.kind == ControlKind::Switch) {
        switches_[c.signal.index] = fp::kSwitchInvalid;
        digital_changed_ = true;
      }
      break;
    }
    case K::Silent: silent_ = true; break;
    case K::Resume: silent_ = false; break;
    case K::Status: status_ = static_cast<fp::PanelStatus>(e.status); break;
    case K::Corrupt: corrupt_left_ += e.count; break;
    case K::End: ended_ = true; break;
  }
}

bool ConsoleEmulator::send(hil::io::CanBus& bus, const fp::Message& message) {
  fp::WireFrame w = encoder_.next(message);
  if (corrupt_left_ > 0) {
    w.data[0] ^= 0x5A;  // a wrong CRC, as a flipped bit on the wire would give
    --corrupt_left_;
  }
  hil::io::CanFrame f;
  f.id = w.can_id;
  f.len = static_cast<uint8_t>(w.data.size());
  std::copy(w.data.begin(), w.data.end(), f.data.begin());
  if (bus.send(f) != hil::io::IoStatus::Ok) return false;
  ++frames_sent_;
  return true;
}

int ConsoleEmulator::tick(hil::io::CanBus& bus, int64_t now_us) {
  if (start_us_ < 0) {
    start_us_ = now_us;
    next_axes_us_ = next_digital_us_ = next_heartbeat_us_ = now_us;
  }
  if (silent_ || ended_) return 0;
  int sent = 0;
  // Heartbeat first at power-up, so the host learns the protocol version
  // before it sees the first control frame.
  if (now_us >= next_heartbeat_us_) {
    fp::HeartbeatFrame hb;
    hb.status = status_;
    hb.uptime_ms = static_cast<uint32_t>((now_us - start_us_) / 1000);
    sent += send(bus, hb);
    next_heartbeat_us_ += period_us(fp::FrameType::Heartbeat);
    if (next_heartbeat_us_ <= now_us) next_heartbeat_us_ = now_us + period_us(fp::FrameType::Heartbeat);
  }
  if (now_us >= next_axes_us_) {
    for (uint8_t group = 0; group < fp::kAxisFrames; ++group) {
      fp::AxesFrame a;
      a.group = group;
      for (std::size_t i = 0; i < fp::kAxesPerFrame; ++i) a.raw[i] = axes_[group * fp::kAxesPerFrame + i];
      sent += send(bus, a);
    }
    next_axes_us_ += period_us(fp::FrameType::Axes0);
    if (next_axes_us_ <= now_us) next_axes_us_ = now_us + period_us(fp::FrameType::Axes0);
  }
  if (now_us >= next_digital_us_ || digital_changed_) {
    sent += send(bus, fp::ButtonsFrame{buttons_});
    fp::SwitchesFrame s;
    s.position = switches_;
    sent += send(bus, s);
    digital_changed_ = false;
    next_digital_us_ = now_us + period_us(fp::FrameType::Buttons);
  }
  return sent;
}

bool ConsoleEmulator::on_frame(const hil::io::CanFrame& frame) {
  if (frame.error || frame.remote || frame.fd || frame.extended) return false;
  const auto r = feedback_decoder_.decode(frame.id, std::span<const uint8_t>(frame.data.data(), frame.len));
  if (!r.ok()) {
    if (r.error != fp::DecodeError::UnknownId) ++feedback_.bad_frames;
    return false;
  }
  const ConsoleFeedback before = feedback_;
  if (const auto* ind = std::get_if<fp::IndicatorsFrame>(&r.message)) {
    feedback_.leds_on = ind->leds_on;
    feedback_.buzzer = ind->buzzer;
  } else if (const auto* d = std::get_if<fp::DisplayFrame>(&r.message)) {
    feedback_.displays[d->index] = *d;
  } else {
    return false;
  }
  ++feedback_.frames;
  return !(before == feedback_);
}

fp::ConsoleInputs ConsoleEmulator::inputs(int64_t now_us) const {
  fp::ConsoleInputs in;
  in.axes = axes_;
  in.buttons = buttons_;
  in.switches = switches_;
  in.status = status_;
  in.uptime_ms = start_us_ < 0 ? 0u : static_cast<uint32_t>((now_us - start_us_) / 1000);
  in.alive_counter = alive_counter_;
  return in;
}

hil::io::ModbusTableSizes ConsoleEmulator::modbus_table_sizes() {
  return {fp::kModbusCoils, fp::kModbusDiscreteInputs, fp::modbus_hr::kCount, fp::modbus_ir::kCount};
}

bool ConsoleEmulator::tick_modbus(hil::io::ModbusServer& server, int64_t now_us) {
  if (start_us_ < 0) {
    start_us_ = now_us;
    next_modbus_cycle_us_ = now_us;
  }
  if (silent_ || ended_ || now_us < next_modbus_cycle_us_) return false;
  constexpr int64_t kCycleUs = 10000;  // the firmware's 10 ms cycle, as the CAN axes period
  next_modbus_cycle_us_ += kCycleUs;
  if (next_modbus_cycle_us_ <= now_us) next_modbus_cycle_us_ = now_us + kCycleUs;
  ++alive_counter_;
  fp::ModbusInputBlock block = fp::encode_inputs(inputs(now_us));
  if (corrupt_left_ > 0) {
    block.registers[fp::modbus_ir::kCrc] ^= 0x5A5A;  // as a firmware serving a torn block would
    --corrupt_left_;
  }
  server.set_inputs(block.registers, block.discrete_bits);
  ++frames_sent_;
  return true;
}

bool ConsoleEmulator::poll_modbus_feedback(const hil::io::ModbusServer& server) {
  const int64_t writes = server.writes_served();
  if (writes == feedback_.frames) return false;
  fp::ModbusFeedbackBlock block;
  block.coil_bits = server.coil_bits();
  server.holding_registers(block.holding);
  const fp::ModbusFeedbackResult r = fp::decode_feedback(block);
  const ConsoleFeedback before = feedback_;
  feedback_.frames = writes;
  if (!r.ok()) {
    ++feedback_.bad_frames;
    return false;
  }
  feedback_.leds_on = r.indicators.leds_on;
  feedback_.buzzer = r.indicators.buzzer;
  for (const auto& d : definition_.displays)
    if (d.source == source_ && d.index < fp::kModbusDisplays) feedback_.displays[d.index] = r.displays[d.index];
  return !(before == feedback_);
}

std::string ConsoleEmulator::feedback_text() const {
  std::ostringstream out;
  out << "leds";
  for (const auto& led : definition_.leds)
    if (led.source == source_)
      out << ' ' << led.name << '=' << (((feedback_.leds_on >> led.bit) & 1u) ? "on" : "off");
  for (const auto& d : definition_.displays) {
    if (d.source != source_) continue;
    const auto it = feedback_.displays.find(d.index);
    out << "; display " << d.name << '=';
    if (it == feedback_.displays.end()) {
      out << '-';
    } else {
      double v = it->second.raw;
      for (int i = 0; i < it->second.decimals; ++i) v /= 10.0;
      out.precision(it->second.decimals);
      out << std::fixed << v;
    }
  }
  out << "; buzzer " << buzzer_text(feedback_.buzzer);
  return out.str();
}

}  // namespace rise::panels
