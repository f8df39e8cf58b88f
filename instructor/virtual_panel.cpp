#include "instructor/virtual_panel.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "hil/input_fault.hpp"
#include "hil/panel_state_message.hpp"
#include "msgs/publisher_session.hpp"

namespace rise::instructor {
namespace fp = rise::firmware_protocol;

namespace {

int16_t unit_to_axis(float unit) {
  // The inverse of firmware_protocol::axis_to_unit: ±1 ↔ ±32767.
  const float clamped = std::clamp(std::isfinite(unit) ? unit : 0.0f, -1.0f, 1.0f);
  return static_cast<int16_t>(std::lround(clamped * 32767.0f));
}

const panels::ControlDefinition* find_control(const panels::PanelDefinition& d, const std::string& name,
                                              panels::ControlKind kind) {
  for (const auto& c : d.controls)
    if (c.name == name && c.kind == kind) return &c;
  return nullptr;
}

}  // namespace

panels::PanelDefinition virtual_definition(panels::PanelDefinition definition, uint32_t timeout_ms) {
  if (definition.sources.size() != 1)
    throw std::runtime_error(definition.file + ": a virtual panel needs a definition with one source, this one has " +
                             std::to_string(definition.sources.size()));
  auto& source = definition.sources[0];
  if (source.is_hid() || source.is_dbc() || source.is_generic_modbus() || source.is_canopen())
    throw std::runtime_error(definition.file + ": source '" + source.name +
                             "': a virtual panel needs a rise-can-v1 or rise-modbus-v1 console, not " + source.protocol);
  source.name = kVirtualSourceName;
  source.timeout_ms = timeout_ms;
  source.recovery_frames = 1;
  return definition;
}

VirtualPanel::VirtualPanel(panels::PanelDefinition definition, uint32_t timeout_ms, std::string client)
    : mapper_(virtual_definition(std::move(definition), timeout_ms)), url_("virtual://" + std::move(client)) {}

std::optional<std::string> VirtualPanel::update(const VirtualControls& controls, int64_t now_us) {
  const auto& d = mapper_.definition();
  fp::ConsoleInputs in;
  // Unbound signals read "not available"; the bound ones start at their safe value.
  in.axes.fill(fp::kAxisInvalid);
  in.switches.fill(fp::kSwitchInvalid);
  for (const auto& c : d.controls) {
    switch (c.kind) {
      case panels::ControlKind::Axis: in.axes[c.signal.index] = unit_to_axis(c.safe_axis); break;
      case panels::ControlKind::Button:
        if (c.safe_button) in.buttons |= 1u << c.signal.index;
        break;
      case panels::ControlKind::Switch:
        if (c.bits.empty()) in.switches[c.signal.index] = c.safe_switch;
        break;
    }
  }
  for (const auto& [name, value] : controls.axes) {
    const auto* c = find_control(d, name, panels::ControlKind::Axis);
    if (!c) return "axis '" + name + "': no such axis in " + d.name;
    in.axes[c->signal.index] = unit_to_axis(value);
  }
  for (const auto& [name, pressed] : controls.buttons) {
    const auto* c = find_control(d, name, panels::ControlKind::Button);
    if (!c) return "button '" + name + "': no such button in " + d.name;
    const uint32_t bit = 1u << c->signal.index;
    in.buttons = pressed ? (in.buttons | bit) : (in.buttons & ~bit);
  }
  for (const auto& [name, label] : controls.switches) {
    const auto* c = find_control(d, name, panels::ControlKind::Switch);
    if (!c) return "switch '" + name + "': no such switch in " + d.name;
    const auto it = std::find(c->positions.begin(), c->positions.end(), label);
    if (it == c->positions.end()) return "switch '" + name + "': no position '" + label + "'";
    const auto position = static_cast<uint8_t>(it - c->positions.begin());
    if (!c->bits.empty()) {
      // A switch read from button inputs: set the bits of its position.
      for (std::size_t b = 0; b < c->bits.size(); ++b) {
        const bool on = c->encoding == panels::BitsEncoding::OneHot ? b == position : ((position >> b) & 1u) != 0;
        const uint32_t bit = 1u << c->bits[b];
        in.buttons = on ? (in.buttons | bit) : (in.buttons & ~bit);
      }
    } else {
      in.switches[c->signal.index] = position;
    }
  }
  in.status = fp::PanelStatus::Operational;
  in.alive_counter = ++alive_;
  mapper_.on_connection(0, true, now_us);
  mapper_.on_inputs(0, in, now_us);
  last_update_us_ = now_us;
  return std::nullopt;
}

void VirtualPanel::disconnect(int64_t now_us) { mapper_.on_connection(0, false, now_us); }

std::string VirtualPanel::apply(const rise_msgs::FaultCommand& command, int64_t now_us) {
  if (command.action == "clear") {
    mapper_.clear_input_faults(command.fault_id, now_us);
    return "";
  }
  if (command.action != "inject") return "action '" + command.action + "': not inject or clear";
  const auto kind = hil::parse_input_fault_kind(command.kind);
  if (!kind) return "'" + command.kind + "' is not an input fault (a virtual panel has no wire)";
  if (command.fault_id.empty()) return "a fault needs an id";
  const auto& d = mapper_.definition();
  const auto control = d.find_control(command.target);
  if (!control) return "no control '" + command.target + "' in panel '" + d.name + "'";
  hil::InputFault f;
  f.id = command.fault_id;
  f.kind = *kind;
  f.control = *control;
  f.value = command.value;
  f.rate = command.rate;
  f.seed = static_cast<uint64_t>(command.seed);
  f.start_us = now_us;
  f.end_us = command.duration_s > 0.0 ? now_us + static_cast<int64_t>(command.duration_s * 1e6) : 0;
  return mapper_.inject_input_fault(std::move(f));
}

void VirtualPanel::note_rejected(const std::string& why, int64_t now_us) {
  rejected_note_ = "rejected: " + why;
  rejected_until_us_ = now_us + 10'000'000;
}

rise_msgs::PanelState VirtualPanel::state(const std::string& trainee_id, int64_t now_us, int64_t utime) {
  const hil::PanelSnapshot snapshot = mapper_.evaluate(now_us);
  auto m = hil::to_message(mapper_.definition(), snapshot, trainee_id, ++seq_, utime, {url_});
  m.publisher = msgs::this_publisher();
  if (now_us < rejected_until_us_) {
    m.active_faults.push_back(rejected_note_);
    m.num_faults = static_cast<int16_t>(m.active_faults.size());
  }
  return m;
}

}  // namespace rise::instructor
