// The Console Builder's model (instructor/console_builder.hpp): the page's
// controls as JSON and back, the check through rise-hild's loader, the
// signals each source has. No server, no sources opened: the fuzz target
// (tests/fuzz/console_builder_fuzz.cpp) links it alone.
#include <json/json.h>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <filesystem>
#include <regex>
#include <tuple>

#include "firmware_protocol/console_can.hpp"
#include "firmware_protocol/console_modbus.hpp"
#include "firmware_protocol/dbc.hpp"
#include "instructor/console_builder.hpp"

#include "instructor/builder_errors.hpp"

namespace rise::instructor {

namespace fs = std::filesystem;
using panels::ControlEntry;
using panels::FieldValue;

namespace {

Json::Value field_json(const FieldValue& v) {
  if (!v.list) return v.scalar;
  Json::Value items(Json::arrayValue);
  for (const auto& item : v.items) items.append(field_json(item));
  return items;
}

std::optional<FieldValue> field_from_json(const Json::Value& v, int depth) {
  FieldValue f;
  if (v.isArray() && depth < 4) {
    f.list = true;
    for (const auto& item : v) {
      auto inner = field_from_json(item, depth + 1);
      if (!inner) return std::nullopt;
      f.items.push_back(*inner);
    }
  } else if (v.isString()) {
    f.scalar = v.asString();
  } else if (v.isBool()) {
    f.scalar = v.asBool() ? "true" : "false";
  } else if (v.isNumeric()) {
    f.scalar = Json::writeString(Json::StreamWriterBuilder(), v);
  } else {
    return std::nullopt;
  }
  return f;
}

// "file:line: key: message" (panels/yaml_reader.hpp) → its parts.
BuilderError console_loader_error(const std::string& what) {
  BuilderError e;
  std::string rest = what;
  if (std::string file; split_location(what, &file, &e.line, &rest)) e.file = fs::path(file).filename().string();
  // Only a path with [ or . is a key here ("controls[2].bit"), not "panel".
  static const std::regex keyed(R"(^([^ :]+): (.*)$)");
  std::smatch m;
  if (std::regex_match(rest, m, keyed) && m[1].str().find_first_of("[.") != std::string::npos) {
    e.key = m[1].str();
    rest = m[2].str();
  }
  e.message = rest;
  return e;
}

std::string hex(uint32_t v, int digits) {
  char text[16];
  std::snprintf(text, sizeof text, "0x%0*X", digits, v);
  return text;
}

// An axis' physical range for a DBC signal: the file's, else what its bits hold.
std::pair<double, double> dbc_range(const firmware_protocol::DbcSignal& s) {
  if (s.maximum > s.minimum) return {s.minimum, s.maximum};
  const double bits = std::min<double>(s.length_bits, 53);
  double lo = s.is_signed ? -std::pow(2.0, bits - 1) : 0.0;
  double hi = s.is_signed ? std::pow(2.0, bits - 1) - 1 : std::pow(2.0, bits) - 1;
  lo = lo * s.factor + s.offset;
  hi = hi * s.factor + s.offset;
  if (lo > hi) std::swap(lo, hi);
  return {lo, hi};
}

}  // namespace

Json::Value controls_json(const std::vector<ControlEntry>& controls) {
  Json::Value out(Json::arrayValue);
  for (const auto& c : controls) {
    Json::Value j, fields(Json::arrayValue);
    j["comment"] = c.comment;
    for (const auto& [k, v] : c.fields) {
      Json::Value pair(Json::arrayValue);
      pair.append(k);
      pair.append(field_json(v));
      fields.append(pair);
    }
    j["fields"] = fields;
    out.append(j);
  }
  return out;
}

std::optional<std::vector<ControlEntry>> controls_from_json(const Json::Value& controls, std::string* error) {
  if (!controls.isArray()) return *error = "expected a list", std::nullopt;
  std::vector<ControlEntry> out;
  for (Json::ArrayIndex i = 0; i < controls.size(); ++i) {
    const std::string where = "controls[" + std::to_string(i) + "]";
    const Json::Value& c = controls[i];
    if (!c.isObject() || !c["fields"].isArray()) return *error = where + ": expected {comment, fields}", std::nullopt;
    ControlEntry e;
    if (c["comment"].isString()) e.comment = c["comment"].asString();
    for (Json::ArrayIndex k = 0; k < c["fields"].size(); ++k) {
      const Json::Value& pair = c["fields"][k];
      const std::string at = where + ".fields[" + std::to_string(k) + "]";
      if (!pair.isArray() || pair.size() != 2 || !pair[0].isString() || pair[0].asString().empty())
        return *error = at + ": expected [key, value]", std::nullopt;
      auto value = field_from_json(pair[1], 0);
      if (!value) return *error = at + ": a value is text, a number, true/false or a list", std::nullopt;
      e.fields.emplace_back(pair[0].asString(), *value);
    }
    out.push_back(std::move(e));
  }
  return out;
}

ConsoleCheck check_console(const std::string& text, const std::vector<ControlEntry>& controls, const std::string& path) {
  ConsoleCheck check;
  try {
    check.yaml = panels::write_panel_controls(text, controls, &check.lines);
    check.definition = panels::parse_panel_definition(check.yaml, path);
  } catch (const std::exception& e) {
    check.errors.push_back(console_loader_error(e.what()));
  }
  return check;
}

Json::Value check_json(const ConsoleCheck& check) {
  Json::Value v;
  v["yaml"] = check.yaml;
  v["ok"] = check.errors.empty();
  Json::Value errors(Json::arrayValue), lines(Json::arrayValue);
  for (const auto& e : check.errors) {
    Json::Value j = builder_error_json(e);
    // The control whose lines hold the error (-1: none).
    int control = -1;
    for (std::size_t i = 0; i < check.lines.size(); ++i)
      if (check.lines[i] <= e.line) control = static_cast<int>(i);
    if (control >= 0 && static_cast<std::size_t>(control) + 1 == check.lines.size() &&
        e.line > check.lines.back() + 1)
      control = -1;  // after the last control: another section's
    j["control"] = control;
    errors.append(j);
  }
  for (int l : check.lines) lines.append(l);
  v["errors"] = errors;
  v["lines"] = lines;
  return v;
}

std::vector<RawSignal> raw_signals(const panels::PanelDefinition& def, const std::vector<ControlEntry>& controls) {
  std::vector<RawSignal> out;
  auto bound = [&](std::size_t source, const std::string& signal) {
    for (const auto& c : def.controls) {
      if (c.source != source) continue;
      if (c.dbc_signal && c.dbc_message->name + "." + c.dbc_signal->name == signal) return true;
      if (!c.dbc_signal && c.hid_signal.empty() && !c.modbus_point && c.bits.empty() &&
          panels::to_string(c.signal) == signal)
        return true;
    }
    return false;
  };
  for (std::size_t s = 0; s < def.sources.size(); ++s) {
    const auto& source = def.sources[s];
    if (source.is_dbc()) {
      for (const auto& m : source.dbc->messages()) {
        if (source.is_j1939() && !m.extended) continue;
        for (const auto& sig : m.signals) {
          RawSignal r{s, m.name + "." + sig.name, sig.length_bits == 1 ? "button" : "axis"};
          r.wire = "CAN " + hex(m.id, m.extended ? 8 : 3) + (m.extended ? " (29-bit)" : "");
          if (r.kind == "axis") std::tie(r.lo, r.hi) = dbc_range(sig);
          if (r.kind == "axis" && !(r.hi > r.lo)) continue;
          r.bound = bound(s, r.signal);
          out.push_back(r);
        }
      }
    } else if (source.is_hid() || source.is_generic_modbus() || source.is_canopen()) {
      for (const auto& c : def.controls) {
        if (c.source != s) continue;
        const ControlEntry* entry = nullptr;
        for (const auto& e : controls)
          if (const FieldValue* n = e.find("name"); n && n->scalar == c.name) entry = &e;
        const FieldValue* signal = entry ? entry->find("signal") : nullptr;
        if (!signal || signal->list) continue;
        const char* kind = c.kind == panels::ControlKind::Axis     ? "axis"
                           : c.kind == panels::ControlKind::Button ? "button"
                                                                   : "switch";
        out.push_back(RawSignal{s, signal->scalar, kind, -1.0, 1.0, true});
      }
    } else {  // rise-can-v1, rise-modbus-v1: the register map of firmware_protocol/README.md
      namespace fp = firmware_protocol;
      const bool modbus = source.is_modbus();
      const auto can = [&](fp::FrameType t) { return "CAN " + hex(fp::can_id(t, source.node), 3); };
      for (std::size_t i = 0; i < fp::kMaxAxes; ++i)
        out.push_back({s, "axis." + std::to_string(i), "axis", -1.0, 1.0, false,
                       modbus ? "input register " + std::to_string(fp::modbus_ir::kAxis0 + i)
                              : can(i < fp::kAxesPerFrame ? fp::FrameType::Axes0 : fp::FrameType::Axes1)});
      for (std::size_t i = 0; i < fp::kMaxButtons; ++i)
        out.push_back({s, "button." + std::to_string(i), "button", -1.0, 1.0, false,
                       modbus ? "discrete input " + std::to_string(i) : can(fp::FrameType::Buttons)});
      for (std::size_t i = 0; i < fp::kMaxSwitches; ++i)
        out.push_back({s, "switch." + std::to_string(i), "switch", -1.0, 1.0, false,
                       modbus ? "input register " + std::to_string(fp::modbus_ir::kSwitch0 + i)
                              : can(fp::FrameType::Switches)});
      for (auto& r : out)
        if (r.source == s) r.bound = bound(s, r.signal);
    }
  }
  return out;
}

}  // namespace rise::instructor
