#include "panels/panel_definition.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>

#include "firmware_protocol/console_can.hpp"
#include "firmware_protocol/dbc.hpp"
#include "firmware_protocol/sdl_mapping.hpp"
#include "panels/canopen_definition.hpp"
#include "panels/yaml_reader.hpp"

#include <filesystem>

namespace rise::panels {
namespace {

namespace fp = rise::firmware_protocol;

std::string control_key(const std::string& name) { return "controls." + name; }

// range: [min, max] of an axis' raw value, which maps to -1..1.
void read_range(const YamlReader& ctx, const YAML::Node& range, const std::string& where, ControlDefinition& c) {
  if (!range.IsSequence() || range.size() != 2) ctx.fail(range, where + ".range", "expected [min, max]");
  c.range_min = ctx.as<double>(range[0], where + ".range");
  c.range_max = ctx.as<double>(range[1], where + ".range");
}

const char* const kModbusSignals =
    "input_register.N, holding_register.N, discrete_input.N, coil.N, input_register.N.bit.B, "
    "holding_register.N.bit.B; N 0..65535, B 0..15";

ModbusPoint read_modbus_point(const YamlReader& ctx, const YAML::Node& node, const std::string& where) {
  const auto text = ctx.require<std::string>(node, "signal", where);
  const auto point = parse_modbus_point(text);
  if (!point) ctx.fail(node["signal"], where + ".signal", "unknown signal '" + text + "' (" + kModbusSignals + ")");
  return *point;
}

ModbusValueType read_modbus_type(const YamlReader& ctx, const YAML::Node& node, const std::string& where) {
  const auto type = ctx.get<std::string>(node, "type", where, "uint16");
  if (type == "uint16") return ModbusValueType::UInt16;
  if (type == "int16") return ModbusValueType::Int16;
  ctx.fail(node["type"], where + ".type", "unknown type '" + type + "' (uint16, int16)");
}

// A control of a "modbus" source: the point it reads; a whole register's
// number type; an axis' range of that number.
void parse_modbus_binding(const YamlReader& ctx, const YAML::Node& node, const std::string& where, ControlDefinition& c) {
  if (node["bits"])
    ctx.fail(node["bits"], where + ".bits", "not for a modbus source: bind the register whose value is the position");
  const ModbusPoint point = read_modbus_point(ctx, node, where);
  const std::string text = to_string(point);
  c.modbus_point = point;
  if (const YAML::Node type = node["type"]) {
    if (point.is_bit()) ctx.fail(type, where + ".type", text + " is one bit: only a whole register has a type");
    if (c.kind == ControlKind::Button)
      ctx.fail(type, where + ".type", "not used by a button (pressed while the register is not 0)");
  }
  c.modbus_type = read_modbus_type(ctx, node, where);
  if (c.kind == ControlKind::Axis) {
    if (point.is_bit())
      ctx.fail(node["signal"], where + ".signal",
               "an axis reads a whole register (input_register.N, holding_register.N), not " + text);
    const YAML::Node range = node["range"];
    if (!range) ctx.fail(node, where + ".range", "missing: an axis of a modbus source maps range: [min, max] to -1..1");
    read_range(ctx, range, where, c);
    if (!(c.range_max > c.range_min)) ctx.fail(range, where + ".range", "needs min < max");
    const bool int16 = c.modbus_type == ModbusValueType::Int16;
    if (c.range_min < (int16 ? -32768.0 : 0.0) || c.range_max > (int16 ? 32767.0 : 65535.0))
      ctx.fail(range, where + ".range",
               std::string("outside what a register holds as ") + (int16 ? "int16 (-32768..32767)" : "uint16 (0..65535)") +
                   (int16 || c.range_min >= 0.0 ? "" : "; type: int16 reads it signed"));
  } else if (node["range"]) {
    ctx.fail(node["range"], where + ".range", "only for an axis");
  }
  const YAML::Node positions = node["positions"];
  if (c.kind == ControlKind::Switch && point.is_bit() && positions.IsSequence() && positions.size() > 2)
    ctx.fail(node["signal"], where + ".signal",
             text + " is one bit: two positions at most (a register holds more)");
}

// A hid source: its device URL (hid:// or evdev://) and an SDL mapping.
void parse_hid_source(const YamlReader& ctx, const YAML::Node& node, const std::string& where, const std::string& file,
                      SourceDefinition& s) {
  s.device = ctx.get<std::string>(node, "device", where, "");
  if (!s.device.empty() && s.device.rfind("hid://", 0) != 0 && s.device.rfind("evdev://", 0) != 0)
    ctx.fail(node["device"], where + ".device",
             "expected hid://VID:PID[?serial=S][&name=TEXT][&interface=N] or evdev://... (/dev/input/eventN, "
             "by-id/NAME, name/NAME, VID:PID)");
  for (const char* k : {"node", "max_counter_delta", "poll_hz", "unit"})
    if (node[k]) ctx.fail(node[k], where + "." + k, "not used by protocol hid");
  s.mapping = ctx.get<std::string>(node, "mapping", where, "");
  if (!s.mapping.empty() && s.mapping != "sdl")
    ctx.fail(node["mapping"], where + ".mapping", "unknown mapping '" + s.mapping + "' (known: sdl)");
  if (s.mapping.empty()) {
    if (node["sdl_db"]) ctx.fail(node["sdl_db"], where + ".sdl_db", "only with mapping: sdl");
    return;
  }
  s.sdl_db_file = beside(file, ctx.require<std::string>(node, "sdl_db", where));
  try {
    s.sdl_db = std::make_shared<const firmware_protocol::SdlControllerDb>(
        firmware_protocol::SdlControllerDb::load(s.sdl_db_file));
  } catch (const std::exception& e) {
    ctx.fail(node["sdl_db"], where + ".sdl_db", e.what());
  }
}

// A J1939 NAME: 64 bits, written in hex (0x8000000000001939) as J1939-81
// tools print it; yaml-cpp would read 0-prefixed text as octal.
uint64_t read_j1939_name(const YamlReader& ctx, const YAML::Node& node, const std::string& key) {
  const auto text = ctx.as<std::string>(node, key);
  std::size_t used = 0;
  try {
    const uint64_t value = std::stoull(text, &used, 16);
    if (used == text.size() && text.size() <= 18 && text[0] != '-') return value;
  } catch (const std::exception&) {
  }
  ctx.fail(node, key, "expected a 64-bit NAME in hex (0x0123456789ABCDEF), not '" + text + "'");
}

uint8_t read_j1939_address(const YamlReader& ctx, const YAML::Node& map, const char* key, const std::string& where,
                           int fallback) {
  constexpr int last = 253;  // 254 is "no address", 255 "everyone"
  if (!map[key]) return static_cast<uint8_t>(fallback);
  const int address = ctx.require<int>(map, key, where);
  if (address < 0 || address > last)
    ctx.fail(map[key], where + "." + key, "must be 0.." + std::to_string(last) + " (a J1939 source address)");
  return static_cast<uint8_t>(address);
}

// A j1939 source: the bridge's own address and NAME, and how the console is found.
void parse_j1939_source(const YamlReader& ctx, const YAML::Node& node, const std::string& where, SourceDefinition& s) {
  s.j1939_address = read_j1939_address(ctx, node, "address", where, 0x80);
  if (node["j1939_name"]) s.j1939_name = read_j1939_name(ctx, node["j1939_name"], where + ".j1939_name");
  if (node["console_name"]) s.console_name = read_j1939_name(ctx, node["console_name"], where + ".console_name");
  s.console_address = read_j1939_address(ctx, node, "console_address", where, 254);
  if (!s.console_name && s.console_address == 254)
    ctx.fail(node, where + ".console_name",
             "missing: a j1939 source needs the console's NAME (console_name) or its fixed console_address");
  if (s.console_address == s.j1939_address)
    ctx.fail(node["console_address"], where + ".console_address", "is the bridge's own address");
}

SourceDefinition parse_source(const YamlReader& ctx, const YAML::Node& node, std::size_t i, const std::string& file) {
  const std::string where = "sources[" + std::to_string(i) + "]";
  ctx.only_keys(node, where,
                {"name", "protocol", "node", "timeout_ms", "recovery_frames", "max_counter_delta", "poll_hz", "unit",
                 "dbc", "device", "mapping", "sdl_db", "eds", "sync_ms", "address", "j1939_name", "console_name",
                 "console_address"});
  SourceDefinition s;
  s.name = ctx.require<std::string>(node, "name", where);
  s.protocol = ctx.require<std::string>(node, "protocol", where);
  if (s.protocol != "rise-can-v1" && s.protocol != "rise-modbus-v1" && s.protocol != "modbus" && s.protocol != "dbc" &&
      s.protocol != "j1939" && s.protocol != "hid" && !s.is_canopen())
    ctx.fail(node["protocol"], where + ".protocol",
             "unknown protocol '" + s.protocol +
                 "' (known: rise-can-v1, rise-modbus-v1, modbus, dbc, j1939, hid, canopen)");
  if (!s.is_canopen())
    for (const char* k : kCanopenSourceKeys)
      if (node[k]) ctx.fail(node[k], where + "." + k, "only for protocol canopen");
  if (s.is_hid()) parse_hid_source(ctx, node, where, file, s);
  else
    for (const char* k : {"device", "mapping", "sdl_db"})
      if (node[k]) ctx.fail(node[k], where + "." + k, "only for protocol hid");
  if (s.is_dbc()) {
    s.dbc_file = beside(file, ctx.require<std::string>(node, "dbc", where));
    try {
      s.dbc = std::make_shared<const firmware_protocol::DbcDatabase>(firmware_protocol::DbcDatabase::load(s.dbc_file));
    } catch (const std::exception& e) {
      ctx.fail(node["dbc"], where + ".dbc", e.what());
    }
    for (const char* k : {"node", "max_counter_delta", "poll_hz", "unit"})
      if (node[k]) ctx.fail(node[k], where + "." + k, "not used by protocol " + s.protocol);
  } else if (node["dbc"]) {
    ctx.fail(node["dbc"], where + ".dbc", "only for protocols dbc and j1939");
  }
  if (s.is_j1939()) parse_j1939_source(ctx, node, where, s);
  else
    for (const char* k : {"address", "j1939_name", "console_name", "console_address"})
      if (node[k]) ctx.fail(node[k], where + "." + k, "only for protocol j1939");
  if (s.is_generic_modbus())
    for (const char* k : {"node", "max_counter_delta", "recovery_frames"})
      if (node[k])
        ctx.fail(node[k], where + "." + k,
                 "not used by protocol modbus (no alive counter or CRC: stale when no poll is answered within "
                 "timeout_ms)");
  if (!s.is_modbus() && (node["poll_hz"] || node["unit"]))
    ctx.fail(node["poll_hz"] ? node["poll_hz"] : node["unit"], where + (node["poll_hz"] ? ".poll_hz" : ".unit"),
             "only for protocols rise-modbus-v1 and modbus");
  s.poll_hz = ctx.get<double>(node, "poll_hz", where, 50.0);
  if (!(s.poll_hz >= 1.0 && s.poll_hz <= 1000.0))
    ctx.fail(node["poll_hz"], where + ".poll_hz", "must be 1..1000");
  const int unit = ctx.get<int>(node, "unit", where, 1);
  if (unit < 1 || unit > 247) ctx.fail(node["unit"], where + ".unit", "must be 1..247");
  s.unit = static_cast<uint8_t>(unit);
  const int node_id = ctx.get<int>(node, "node", where, 0);
  if (node_id < 0 || node_id > (s.is_canopen() ? 127 : 15))
    ctx.fail(node["node"], where + ".node", s.is_canopen() ? "a CANopen node id is 1..127" : "must be 0..15");
  s.node = static_cast<uint8_t>(node_id);
  const int timeout = ctx.get<int>(node, "timeout_ms", where, s.is_hid() ? 1000 : 50);
  if ((timeout < 5 && !(s.is_hid() && timeout == 0)) || timeout > 10000)
    ctx.fail(node["timeout_ms"], where + ".timeout_ms", s.is_hid() ? "must be 0 (never stale) or 5..10000" : "must be 5..10000");
  s.timeout_ms = static_cast<uint32_t>(timeout);
  const int recovery = ctx.get<int>(node, "recovery_frames", where, 3);
  if (recovery < 1 || recovery > 1000)
    ctx.fail(node["recovery_frames"], where + ".recovery_frames", "must be 1..1000");
  s.recovery_frames = static_cast<uint32_t>(recovery);
  const int delta = ctx.get<int>(node, "max_counter_delta", where, 1);
  if (delta < 1 || delta > 14)
    ctx.fail(node["max_counter_delta"], where + ".max_counter_delta", "must be 1..14");
  s.max_counter_delta = static_cast<uint8_t>(delta);
  if (s.is_canopen()) parse_canopen_source(ctx, node, where, file, s);
  return s;
}

std::size_t resolve_source(const YamlReader& ctx, const PanelDefinition& def, const YAML::Node& node,
                           const std::string& where) {
  const YAML::Node src = node["source"];
  if (!src) {
    if (def.sources.size() == 1) return 0;
    ctx.fail(node, where + ".source", "missing (the panel has several sources)");
  }
  const auto name = ctx.as<std::string>(src, where + ".source");
  const auto index = def.find_source(name);
  if (!index) ctx.fail(src, where + ".source", "unknown source '" + name + "'");
  return *index;
}

// A dbc source's control: MESSAGE.SIGNAL of the source's DBC, an axis' range
// from the DBC unless given.
void parse_dbc_binding(const YamlReader& ctx, const SourceDefinition& source, const YAML::Node& node,
                       const std::string& where, ControlDefinition& c) {
  const auto text = ctx.require<std::string>(node, "signal", where);
  const auto dot = text.find('.');
  const firmware_protocol::DbcMessage* message =
      dot == std::string::npos ? nullptr : source.dbc->find(std::string_view(text).substr(0, dot));
  const firmware_protocol::DbcSignal* signal =
      message ? message->signal(std::string_view(text).substr(dot + 1)) : nullptr;
  if (!signal)
    ctx.fail(node["signal"], where + ".signal",
             "no signal '" + text + "' (MESSAGE.SIGNAL) in " + source.dbc_file);
  if (node["bits"]) ctx.fail(node["bits"], where + ".bits", "not for a dbc source");
  if (source.is_j1939() && !message->extended)
    ctx.fail(node["signal"], where + ".signal",
             "message " + message->name + " has an 11-bit id: a J1939 PGN needs a 29-bit one (BO_ id with bit 31 set)");
  c.dbc_message = message;
  c.dbc_signal = signal;
  if (c.kind == ControlKind::Axis) {
    if (const YAML::Node range = node["range"]) {
      read_range(ctx, range, where, c);
    } else {
      c.range_min = signal->minimum;
      c.range_max = signal->maximum;
    }
    if (!(c.range_max > c.range_min))
      ctx.fail(node["range"] ? node["range"] : node, where + ".range",
               "needs min < max (the DBC gives none for " + text + ")");
  }
}

// A hid source's control: the name of a report signal (or an evdev code's,
// or SDL's sdl.NAME with mapping: sdl).
void parse_hid_binding(const YamlReader& ctx, const SourceDefinition& source, const YAML::Node& node,
                       const std::string& where, ControlDefinition& c) {
  c.hid_signal = ctx.require<std::string>(node, "signal", where);
  if (c.hid_signal.empty()) ctx.fail(node["signal"], where + ".signal", "must not be empty");
  if (c.hid_signal.rfind("sdl.", 0) == 0) {
    const std::string name = c.hid_signal.substr(4);
    if (source.mapping != "sdl")
      ctx.fail(node["signal"], where + ".signal", "sdl.NAME needs mapping: sdl on source '" + source.name + "'");
    if (!firmware_protocol::is_sdl_axis(name) && !firmware_protocol::is_sdl_button(name))
      ctx.fail(node["signal"], where + ".signal",
               "SDL has no '" + name + "' (known: " + firmware_protocol::sdl_names() + ")");
  }
  if (node["bits"]) ctx.fail(node["bits"], where + ".bits", "not for a hid source");
  // Axes arrive normalised by the report decoder (-1..1 or 0..1).
  c.range_min = -1.0;
  c.range_max = 1.0;
}

// A switch read from several button inputs: no switch signal of its own.
void parse_switch_bits(const YamlReader& ctx, const YAML::Node& node, const YAML::Node& bits, const std::string& where,
                       ControlDefinition& c) {
  if (c.kind != ControlKind::Switch) ctx.fail(bits, where + ".bits", "only a switch can be read from bits");
  if (node["signal"]) ctx.fail(node["signal"], where + ".signal", "give either signal or bits, not both");
  if (!bits.IsSequence() || bits.size() < 1 || bits.size() > 8)
    ctx.fail(bits, where + ".bits", "expected a list of 1..8 button signals");
  for (const auto& b : bits) {
    const auto text = ctx.as<std::string>(b, where + ".bits");
    const auto ref = parse_signal(text);
    if (!ref || ref->kind != SignalRef::Kind::Button)
      ctx.fail(b, where + ".bits", "'" + text + "' is not a button signal (button.0-31)");
    c.bits.push_back(ref->index);
  }
  const auto encoding = ctx.get<std::string>(node, "encoding", where, "binary");
  if (encoding == "binary") c.encoding = BitsEncoding::Binary;
  else if (encoding == "one_hot") c.encoding = BitsEncoding::OneHot;
  else ctx.fail(node["encoding"], where + ".encoding", "unknown encoding '" + encoding + "' (binary, one_hot)");
  c.signal = SignalRef{SignalRef::Kind::Button, c.bits.front()};
}

// The protocol signal (axis.N, button.N, switch.N) and whether it fits the control's kind.
void parse_protocol_signal(const YamlReader& ctx, const YAML::Node& node, const std::string& where, bool named_signals,
                           const std::string& kind, ControlDefinition& c) {
  const auto signal_text = named_signals ? std::string("axis.0")
                           : c.bits.empty() ? ctx.require<std::string>(node, "signal", where)
                                            : to_string(c.signal);
  const auto signal = parse_signal(signal_text);
  if (!signal)
    ctx.fail(node["signal"], where + ".signal",
             "unknown signal '" + signal_text + "' (axis.0-5, button.0-31, switch.0-5)");
  c.signal = *signal;
  const bool kind_matches = !c.bits.empty() || named_signals ||
      (c.kind == ControlKind::Axis && signal->kind == SignalRef::Kind::Axis) ||
      (c.kind == ControlKind::Button && signal->kind == SignalRef::Kind::Button) ||
      (c.kind == ControlKind::Switch && signal->kind == SignalRef::Kind::Switch);
  if (!kind_matches)
    ctx.fail(node["signal"], where + ".signal",
             "signal '" + signal_text + "' does not fit a control of kind " + kind);
}

// The dead-man or e-stop role, and whether the control moves the robot. Returns the role's name.
std::string parse_role(const YamlReader& ctx, const YAML::Node& node, const std::string& where, ControlDefinition& c) {
  const auto role = ctx.get<std::string>(node, "role", where, "none");
  if (role == "none") c.role = ControlRole::None;
  else if (role == "deadman") c.role = ControlRole::Deadman;
  else if (role == "estop") c.role = ControlRole::Estop;
  else ctx.fail(node["role"], where + ".role", "unknown role '" + role + "' (deadman, estop)");
  if (c.role != ControlRole::None && c.kind != ControlKind::Button)
    ctx.fail(node["role"], where + ".role", "only a button can be the " + role);

  c.motion = ctx.get<bool>(node, "motion", where, false);
  if (c.motion && c.role != ControlRole::None)
    ctx.fail(node["motion"], where + ".motion", "the " + role + " cannot be a motion control");
  return role;
}

void parse_axis_settings(const YamlReader& ctx, const YAML::Node& node, const YAML::Node& safe, const std::string& where,
                         ControlDefinition& c) {
  c.safe_axis = ctx.as<float>(safe, where + ".safe");
  if (!(c.safe_axis >= -1.0f && c.safe_axis <= 1.0f))
    ctx.fail(safe, where + ".safe", "an axis' safe value must be in -1..1");
  c.deadband = ctx.get<float>(node, "deadband", where, 0.0f);
  if (!(c.deadband >= 0.0f && c.deadband < 0.5f))
    ctx.fail(node["deadband"], where + ".deadband", "must be in 0..0.5");
  c.invert = ctx.get<bool>(node, "invert", where, false);
  c.scale = ctx.get<float>(node, "scale", where, 1.0f);
  if (!(c.scale > 0.0f && c.scale <= 1.0f))
    ctx.fail(node["scale"], where + ".scale", "must be in (0, 1]");
  c.expo = ctx.get<float>(node, "expo", where, 0.0f);
  if (!(c.expo >= 0.0f && c.expo <= 1.0f)) ctx.fail(node["expo"], where + ".expo", "must be in 0..1");
  c.lowpass_ms = ctx.get<float>(node, "lowpass_ms", where, 0.0f);
  if (!(c.lowpass_ms >= 0.0f && c.lowpass_ms <= 10000.0f))
    ctx.fail(node["lowpass_ms"], where + ".lowpass_ms", "must be in 0..10000");
  for (const char* k : {"mode", "debounce_ms", "long_press_ms", "pulse_ms", "positions"})
    if (node[k]) ctx.fail(node[k], where + "." + k, "not allowed on an axis");
}

void parse_button_settings(const YamlReader& ctx, const YAML::Node& node, const YAML::Node& safe,
                           const std::string& where, const std::string& role, ControlDefinition& c) {
  c.safe_button = ctx.as<bool>(safe, where + ".safe");
  for (const char* k : {"deadband", "invert", "scale", "expo", "lowpass_ms", "positions"})
    if (node[k]) ctx.fail(node[k], where + "." + k, "not allowed on a button");
  const auto mode = ctx.get<std::string>(node, "mode", where, "direct");
  if (mode == "direct") c.behaviour = ButtonBehaviour::Direct;
  else if (mode == "toggle") c.behaviour = ButtonBehaviour::Toggle;
  else if (mode == "long_press") c.behaviour = ButtonBehaviour::LongPress;
  else if (mode == "edge") c.behaviour = ButtonBehaviour::Edge;
  else ctx.fail(node["mode"], where + ".mode", "unknown mode '" + mode + "' (direct, toggle, long_press, edge)");
  if (c.role != ControlRole::None && c.behaviour != ButtonBehaviour::Direct)
    ctx.fail(node["mode"], where + ".mode", "the " + role + " must be mode: direct");
  const auto ms = [&](const char* key, int fallback) {
    const int v = ctx.get<int>(node, key, where, fallback);
    if (v < 0 || v > 60000) ctx.fail(node[key], where + "." + key, "must be 0..60000");
    return static_cast<uint32_t>(v);
  };
  c.debounce_ms = ms("debounce_ms", 0);
  c.long_press_ms = ms("long_press_ms", 800);
  c.pulse_ms = ms("pulse_ms", 100);
}

void parse_switch_settings(const YamlReader& ctx, const YAML::Node& node, const YAML::Node& safe,
                           const std::string& where, ControlDefinition& c) {
  const YAML::Node positions = node["positions"];
  if (!positions || !positions.IsSequence() || positions.size() < 2)
    ctx.fail(positions ? positions : node, where + ".positions",
             "a switch needs a list of at least two position labels");
  for (const auto& p : positions) c.positions.push_back(ctx.as<std::string>(p, where + ".positions"));
  const auto safe_label = ctx.as<std::string>(safe, where + ".safe");
  bool found = false;
  for (std::size_t k = 0; k < c.positions.size(); ++k)
    if (c.positions[k] == safe_label) {
      c.safe_switch = static_cast<uint8_t>(k);
      found = true;
    }
  if (!found)
    ctx.fail(safe, where + ".safe", "'" + safe_label + "' is not one of the positions");
  for (const char* k : {"deadband", "invert", "scale", "expo", "lowpass_ms", "mode", "debounce_ms",
                        "long_press_ms", "pulse_ms"})
    if (node[k]) ctx.fail(node[k], where + "." + k, "not allowed on a switch");
  if (c.encoding == BitsEncoding::Binary && !c.bits.empty() && (1u << c.bits.size()) < c.positions.size())
    ctx.fail(node["bits"], where + ".bits", "too few bits for " + std::to_string(c.positions.size()) + " positions");
  if (c.encoding == BitsEncoding::OneHot && c.bits.size() != c.positions.size())
    ctx.fail(node["bits"], where + ".bits", "one_hot needs one bit per position");
}

ControlDefinition parse_control(const YamlReader& ctx, const PanelDefinition& def,
                                const YAML::Node& node, std::size_t i) {
  std::string where = "controls[" + std::to_string(i) + "]";
  ctx.only_keys(node, where,
                {"name", "kind", "source", "signal", "bits", "encoding", "range", "type", "role", "motion", "deadband",
                 "invert", "scale", "expo", "lowpass_ms", "mode", "debounce_ms", "long_press_ms",
                 "pulse_ms", "safe", "positions"});
  ControlDefinition c;
  c.line = node.Mark().line + 1;
  c.name = ctx.require<std::string>(node, "name", where);
  if (c.name.empty()) ctx.fail(node["name"], where + ".name", "must not be empty");
  where = control_key(c.name);

  const auto kind = ctx.require<std::string>(node, "kind", where);
  if (kind == "axis") c.kind = ControlKind::Axis;
  else if (kind == "button") c.kind = ControlKind::Button;
  else if (kind == "switch") c.kind = ControlKind::Switch;
  else ctx.fail(node["kind"], where + ".kind", "unknown kind '" + kind + "' (axis, button, switch)");

  c.source = resolve_source(ctx, def, node, where);
  const SourceDefinition& source = def.sources[c.source];
  // Sources whose controls bind names of the device, not axis.N / button.N / switch.N.
  const bool named_signals = source.is_dbc() || source.is_hid() || source.is_generic_modbus() || source.is_canopen();
  if (source.is_dbc()) {
    parse_dbc_binding(ctx, source, node, where, c);
  } else if (source.is_canopen()) {
    parse_canopen_binding(ctx, source, node, where, c);
  } else if (node["range"] && !source.is_generic_modbus()) {
    ctx.fail(node["range"], where + ".range", "only for controls of a dbc, canopen or modbus source");
  }
  if (source.is_generic_modbus()) parse_modbus_binding(ctx, node, where, c);
  else if (node["type"]) ctx.fail(node["type"], where + ".type", "only for controls of a modbus source");
  if (source.is_hid()) parse_hid_binding(ctx, source, node, where, c);
  if (named_signals) {
    // no protocol signal to parse
  } else if (const YAML::Node bits = node["bits"]) {
    parse_switch_bits(ctx, node, bits, where, c);
  } else if (node["encoding"]) {
    ctx.fail(node["encoding"], where + ".encoding", "only with bits");
  }
  parse_protocol_signal(ctx, node, where, named_signals, kind, c);
  const std::string role = parse_role(ctx, node, where, c);

  const YAML::Node safe = node["safe"];
  if (!safe) ctx.fail(node, where + ".safe", "missing: every control declares its safe value");
  switch (c.kind) {
    case ControlKind::Axis: parse_axis_settings(ctx, node, safe, where, c); break;
    case ControlKind::Button: parse_button_settings(ctx, node, safe, where, role, c); break;
    case ControlKind::Switch: parse_switch_settings(ctx, node, safe, where, c); break;
  }
  return c;
}

// What a modbus source's LED or display writes: a coil (LEDs only) or a
// whole holding register, each written by one of them only.
ModbusPoint read_written_point(const YamlReader& ctx, const YAML::Node& n, const std::string& where, bool led,
                               std::set<std::pair<std::size_t, ModbusPoint>>& written, std::size_t source) {
  const ModbusPoint point = read_modbus_point(ctx, n, where);
  const bool coil = point.table == ModbusTable::Coils;
  if (!(point.table == ModbusTable::HoldingRegisters && point.bit < 0) && !(led && coil))
    ctx.fail(n["signal"], where + ".signal",
             to_string(point) + " cannot be written: " +
                 (led ? "an LED is a coil.N or a holding_register.N (written 1 / 0)" : "a display is a holding_register.N"));
  if (!written.insert({source, point}).second)
    ctx.fail(n["signal"], where + ".signal", to_string(point) + " is already written by another LED or display");
  return point;
}

// A feedback output of a hid source: `signal:` names an output signal of the
// device's descriptor, bound once per source.
std::string hid_output_signal(const YamlReader& ctx, const YAML::Node& n, const std::string& where, std::size_t source,
                              std::set<std::pair<std::size_t, std::string>>& bound, const char* what) {
  std::string signal = ctx.require<std::string>(n, "signal", where);
  if (signal.empty()) ctx.fail(n["signal"], where + ".signal", "must not be empty");
  if (!bound.insert({source, signal}).second)
    ctx.fail(n["signal"], where + ".signal", std::string("output signal already bound to another ") + what);
  return signal;
}

void parse_feedback(const YamlReader& ctx, PanelDefinition& def, const YAML::Node& node) {
  ctx.only_keys(node, "feedback", {"leds", "displays", "buzzer", "rumble"});
  std::set<std::string> names;
  std::set<std::pair<std::size_t, ModbusPoint>> written;  // modbus sources' points
  std::set<std::pair<std::size_t, const void*>> pdo_written;  // canopen sources' RPDO objects
  if (const YAML::Node leds = node["leds"]) {
    if (!leds.IsSequence()) ctx.fail(leds, "feedback.leds", "expected a list");
    std::set<std::pair<std::size_t, int>> bits;
    std::set<std::pair<std::size_t, std::string>> hid_signals;
    for (std::size_t i = 0; i < leds.size(); ++i) {
      const YAML::Node n = leds[i];
      std::string where = "feedback.leds[" + std::to_string(i) + "]";
      ctx.only_keys(n, where, {"name", "source", "bit", "signal"});
      LedDefinition led;
      led.name = ctx.require<std::string>(n, "name", where);
      led.line = n.Mark().line + 1;
      where = "feedback.leds." + led.name;
      if (!names.insert(led.name).second) ctx.fail(n["name"], where, "duplicate feedback name");
      led.source = resolve_source(ctx, def, n, where);
      if (def.sources[led.source].is_hid()) {
        // A HID device's LEDs are fields of its output reports, named like its inputs.
        if (n["bit"])
          ctx.fail(n["bit"], where + ".bit",
                   "a hid source's LED is an output signal of the device: signal: NAME (e.g. usage_0008_0001)");
        led.hid_signal = hid_output_signal(ctx, n, where, led.source, hid_signals, "LED");
        def.leds.push_back(led);
        continue;
      }
      if (def.sources[led.source].is_canopen()) {
        if (n["bit"]) ctx.fail(n["bit"], where + ".bit", "a canopen source's LED is an RPDO-mapped object: signal: NAME");
        parse_canopen_output(ctx, def.sources[led.source], n, where, led.pdo_message, led.pdo_signal);
        if (!pdo_written.insert({led.source, led.pdo_signal}).second)
          ctx.fail(n["signal"], where + ".signal", "already written by another LED or display");
        def.leds.push_back(led);
        continue;
      }
      if (def.sources[led.source].is_generic_modbus()) {
        if (n["bit"])
          ctx.fail(n["bit"], where + ".bit", "a modbus source's LED is a coil or a holding register: signal: coil.N");
        led.modbus_point = read_written_point(ctx, n, where, true, written, led.source);
        def.leds.push_back(led);
        continue;
      }
      if (n["signal"])
        ctx.fail(n["signal"], where + ".signal", "only for an LED of a hid source (here: bit: 0..31)");
      const int bit = ctx.require<int>(n, "bit", where);
      if (bit < 0 || bit >= static_cast<int>(fp::kMaxLeds))
        ctx.fail(n["bit"], where + ".bit", "must be 0..31");
      if (!bits.insert({led.source, bit}).second)
        ctx.fail(n["bit"], where + ".bit", "LED bit already used");
      led.bit = static_cast<uint8_t>(bit);
      def.leds.push_back(led);
    }
  }
  if (const YAML::Node rumble = node["rumble"]) {
    if (!rumble.IsSequence()) ctx.fail(rumble, "feedback.rumble", "expected a list");
    std::set<std::pair<std::size_t, std::string>> bound;
    for (std::size_t i = 0; i < rumble.size(); ++i) {
      const YAML::Node n = rumble[i];
      std::string where = "feedback.rumble[" + std::to_string(i) + "]";
      ctx.only_keys(n, where, {"name", "source", "signal"});
      RumbleDefinition r;
      r.name = ctx.require<std::string>(n, "name", where);
      r.line = n.Mark().line + 1;
      where = "feedback.rumble." + r.name;
      if (!names.insert(r.name).second) ctx.fail(n["name"], where, "duplicate feedback name");
      r.source = resolve_source(ctx, def, n, where);
      if (!def.sources[r.source].is_hid())
        ctx.fail(n["source"] ? n["source"] : n, where + ".source",
                 "rumble is an output signal of a hid source's device");
      r.hid_signal = hid_output_signal(ctx, n, where, r.source, bound, "rumble");
      def.rumbles.push_back(r);
    }
  }
  if (const YAML::Node displays = node["displays"]) {
    if (!displays.IsSequence()) ctx.fail(displays, "feedback.displays", "expected a list");
    for (std::size_t i = 0; i < displays.size(); ++i) {
      const YAML::Node n = displays[i];
      std::string where = "feedback.displays[" + std::to_string(i) + "]";
      ctx.only_keys(n, where, {"name", "source", "index", "signal", "type", "decimals"});
      DisplayDefinition d;
      d.name = ctx.require<std::string>(n, "name", where);
      where = "feedback.displays." + d.name;
      if (!names.insert(d.name).second) ctx.fail(n["name"], where, "duplicate feedback name");
      d.source = resolve_source(ctx, def, n, where);
      if (def.sources[d.source].is_hid()) ctx.fail(n, where + ".source", "a hid source has no displays");
      if (def.sources[d.source].is_canopen()) {
        for (const char* k : {"index", "type"})
          if (n[k]) ctx.fail(n[k], where + "." + k, "a canopen source's display is an RPDO-mapped object: signal: NAME");
        parse_canopen_output(ctx, def.sources[d.source], n, where, d.pdo_message, d.pdo_signal);
        if (!pdo_written.insert({d.source, d.pdo_signal}).second)
          ctx.fail(n["signal"], where + ".signal", "already written by another LED or display");
      } else if (def.sources[d.source].is_generic_modbus()) {
        if (n["index"])
          ctx.fail(n["index"], where + ".index", "a modbus source's display is a holding register: signal: holding_register.N");
        d.modbus_point = read_written_point(ctx, n, where, false, written, d.source);
        d.modbus_type = read_modbus_type(ctx, n, where);
      } else {
        for (const char* k : {"signal", "type"})
          if (n[k]) ctx.fail(n[k], where + "." + k, "only for a display of a modbus source (here: index: 0..255)");
        const int index = ctx.require<int>(n, "index", where);
        if (index < 0 || index > 255) ctx.fail(n["index"], where + ".index", "must be 0..255");
        d.index = static_cast<uint8_t>(index);
      }
      const int decimals = ctx.get<int>(n, "decimals", where, 0);
      if (decimals < 0 || decimals > 9) ctx.fail(n["decimals"], where + ".decimals", "must be 0..9");
      d.decimals = static_cast<uint8_t>(decimals);
      def.displays.push_back(d);
    }
  }
  if (const YAML::Node buzzer = node["buzzer"]) {
    ctx.only_keys(buzzer, "feedback.buzzer", {"source"});
    def.buzzer_source = resolve_source(ctx, def, buzzer, "feedback.buzzer");
    if (def.sources[*def.buzzer_source].is_hid()) ctx.fail(buzzer, "feedback.buzzer.source", "a hid source has no buzzer");
    if (def.sources[*def.buzzer_source].is_canopen())
      ctx.fail(buzzer, "feedback.buzzer.source", "a canopen source has no buzzer (light an RPDO-mapped LED instead)");
    if (def.sources[*def.buzzer_source].is_generic_modbus())
      ctx.fail(buzzer, "feedback.buzzer.source", "a modbus source has no buzzer (light an LED on its coil instead)");
  }
}


// The points of a modbus source that its controls read: never one its
// feedback writes (the control would read our own LED back), and each
// table's span from the lowest to the highest address within one request,
// as the bridge reads each table in one request per poll (Modbus
// Application Protocol V1.1b3 §6.1-6.4: 2000 bits, 125 registers). A
// modbus source is healthy while its polls are answered: it needs a point
// to poll.
void check_modbus_points(const YamlReader& ctx, const PanelDefinition& def, const YAML::Node& root) {
  const YAML::Node controls = root["controls"];
  for (std::size_t s = 0; s < def.sources.size(); ++s)
    if (def.sources[s].is_generic_modbus() &&
        std::none_of(def.controls.begin(), def.controls.end(), [&](const auto& c) { return c.source == s; }))
      ctx.fail(root["sources"][s], "sources[" + std::to_string(s) + "]",
               "no control reads source '" + def.sources[s].name +
                   "': a modbus source is trusted while its polls are answered, and it needs a point to poll");
  std::map<std::pair<std::size_t, ModbusTable>, std::pair<uint16_t, uint16_t>> spans;
  for (std::size_t i = 0; i < def.controls.size(); ++i) {
    const ControlDefinition& c = def.controls[i];
    if (!c.modbus_point) continue;
    const ModbusPoint& p = *c.modbus_point;
    const YAML::Node at = controls[i]["signal"];
    const std::string where = control_key(c.name) + ".signal";
    for (const auto& led : def.leds)
      if (led.source == c.source && led.modbus_point && p.table == led.modbus_point->table &&
          p.address == led.modbus_point->address)
        ctx.fail(at, where, to_string(p) + " is written by the LED '" + led.name + "': a control cannot read it");
    for (const auto& d : def.displays)
      if (d.source == c.source && d.modbus_point && p.table == d.modbus_point->table &&
          p.address == d.modbus_point->address)
        ctx.fail(at, where, to_string(p) + " is written by the display '" + d.name + "': a control cannot read it");
    const auto it = spans.try_emplace({c.source, p.table}, p.address, p.address).first;
    auto& [lo, hi] = it->second;
    lo = std::min(lo, p.address);
    hi = std::max(hi, p.address);
    const int count = hi - lo + 1;
    const int most = p.bit_table() ? 2000 : 125;
    if (count > most)
      ctx.fail(at, where,
               to_string(p) + " makes the poll read " + to_string(p.table) + "s " + std::to_string(lo) + ".." +
                   std::to_string(hi) + " (" + std::to_string(count) + "), more than one request reads (" +
                   std::to_string(most) + ")");
  }
}

}  // namespace

std::optional<std::size_t> PanelDefinition::find_control(const std::string& control) const {
  for (std::size_t i = 0; i < controls.size(); ++i)
    if (controls[i].name == control) return i;
  return std::nullopt;
}

std::optional<std::size_t> PanelDefinition::find_source(const std::string& source) const {
  for (std::size_t i = 0; i < sources.size(); ++i)
    if (sources[i].name == source) return i;
  return std::nullopt;
}

std::optional<SignalRef> parse_signal(const std::string& text) {
  const auto dot = text.find('.');
  if (dot == std::string::npos || dot + 1 >= text.size()) return std::nullopt;
  const std::string kind = text.substr(0, dot);
  const std::string digits = text.substr(dot + 1);
  if (digits.size() > 2 || digits.find_first_not_of("0123456789") != std::string::npos)
    return std::nullopt;
  const int index = std::stoi(digits);
  SignalRef ref;
  ref.index = static_cast<uint8_t>(index);
  if (kind == "axis" && index < static_cast<int>(fp::kMaxAxes)) ref.kind = SignalRef::Kind::Axis;
  else if (kind == "button" && index < static_cast<int>(fp::kMaxButtons))
    ref.kind = SignalRef::Kind::Button;
  else if (kind == "switch" && index < static_cast<int>(fp::kMaxSwitches))
    ref.kind = SignalRef::Kind::Switch;
  else return std::nullopt;
  return ref;
}

std::string to_string(const SignalRef& signal) {
  const char* kind = signal.kind == SignalRef::Kind::Axis     ? "axis"
                     : signal.kind == SignalRef::Kind::Button ? "button"
                                                              : "switch";
  return std::string(kind) + "." + std::to_string(signal.index);
}

PanelDefinition parse_panel_definition(const std::string& text, const std::string& file) {
  const YamlReader ctx(file, ValueWording::NameType);
  YAML::Node root = ctx.load_text(text);
  if (!root || !root.IsMap()) ctx.fail(root, "", "expected a mapping with panel, sources, controls");
  ctx.only_keys(root, "", {"panel", "publish_hz", "sources", "controls", "feedback"});

  PanelDefinition def;
  def.file = file;
  def.name = ctx.require<std::string>(root, "panel", "");
  def.publish_hz = ctx.get<double>(root, "publish_hz", "", 100.0);
  if (!(def.publish_hz >= 1.0 && def.publish_hz <= 1000.0))
    ctx.fail(root["publish_hz"], "publish_hz", "must be 1..1000");

  const YAML::Node sources = root["sources"];
  if (!sources || !sources.IsSequence() || sources.size() == 0)
    ctx.fail(sources ? sources : root, "sources", "a list of at least one source is required");
  for (std::size_t i = 0; i < sources.size(); ++i) {
    auto s = parse_source(ctx, sources[i], i, file);
    if (def.find_source(s.name))
      ctx.fail(sources[i]["name"], "sources[" + std::to_string(i) + "].name",
               "duplicate source '" + s.name + "'");
    def.sources.push_back(std::move(s));
  }

  const YAML::Node controls = root["controls"];
  if (!controls || !controls.IsSequence() || controls.size() == 0)
    ctx.fail(controls ? controls : root, "controls", "a list of at least one control is required");
  std::set<std::tuple<std::size_t, int, int>> bound;
  std::set<std::pair<std::size_t, const void*>> dbc_bound;
  std::set<std::pair<std::size_t, std::string>> hid_bound;
  std::set<std::pair<std::size_t, ModbusPoint>> modbus_bound;
  bool has_deadman = false;
  bool has_motion = false;
  for (std::size_t i = 0; i < controls.size(); ++i) {
    auto c = parse_control(ctx, def, controls[i], i);
    if (def.find_control(c.name))
      ctx.fail(controls[i]["name"], control_key(c.name) + ".name", "duplicate control name");
    if (c.dbc_signal || !c.hid_signal.empty() || c.modbus_point) {
      if (c.dbc_signal     ? !dbc_bound.insert({c.source, c.dbc_signal}).second
          : c.modbus_point ? !modbus_bound.insert({c.source, *c.modbus_point}).second
                           : !hid_bound.insert({c.source, c.hid_signal}).second)
        ctx.fail(controls[i]["signal"], control_key(c.name) + ".signal", "signal already bound to another control");
      if (c.role == ControlRole::Deadman) {
        if (has_deadman) ctx.fail(controls[i]["role"], control_key(c.name) + ".role", "a second dead-man");
        has_deadman = true;
      }
      has_motion = has_motion || c.motion;
      def.controls.push_back(std::move(c));
      continue;
    }
    std::vector<SignalRef> uses{c.signal};
    for (const uint8_t b : c.bits) uses.push_back(SignalRef{SignalRef::Kind::Button, b});
    if (!c.bits.empty()) uses.erase(uses.begin());
    for (const auto& use : uses)
      if (!bound.insert({c.source, static_cast<int>(use.kind), use.index}).second)
        ctx.fail(controls[i][c.bits.empty() ? "signal" : "bits"], control_key(c.name) + (c.bits.empty() ? ".signal" : ".bits"),
                 "signal '" + to_string(use) + "' is already bound to another control");
    if (c.role == ControlRole::Deadman) {
      if (has_deadman) ctx.fail(controls[i]["role"], control_key(c.name) + ".role", "a second dead-man");
      has_deadman = true;
    }
    has_motion = has_motion || c.motion;
    def.controls.push_back(std::move(c));
  }
  if (has_motion && !has_deadman)
    ctx.fail(controls, "controls", "motion controls need a control with role: deadman");

  if (const YAML::Node feedback = root["feedback"]) parse_feedback(ctx, def, feedback);
  check_modbus_points(ctx, def, root);
  return def;
}

PanelDefinition load_panel_definition(const std::string& path) {
  return parse_panel_definition(read_text_file(path), path);
}

}  // namespace rise::panels
