#include "panels/timeline.hpp"

#include "panels/yaml_reader.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace rise::panels {
namespace {

[[noreturn]] void fail(const std::string& file, int line, const std::string& what) {
  throw std::runtime_error(file + ":" + std::to_string(line) + ": " + what);
}

bool parse_double(const std::string& text, double& out) {
  try {
    std::size_t used = 0;
    out = std::stod(text, &used);
    return used == text.size() && std::isfinite(out);
  } catch (const std::exception&) {
    return false;
  }
}

uint8_t parse_status(const std::string& file, int line, const std::string& text) {
  if (text == "init") return 0;
  if (text == "operational") return 1;
  if (text == "fault") return 2;
  if (text == "shutdown") return 3;
  fail(file, line, "@status: unknown status '" + text + "' (init, operational, fault, shutdown)");
}

}  // namespace

Timeline parse_timeline(const std::string& text, const std::string& file,
                        const PanelDefinition& definition) {
  Timeline timeline;
  timeline.file = file;
  std::istringstream in(text);
  std::string raw;
  int line = 0;
  double last_time = 0.0;
  while (std::getline(in, raw)) {
    ++line;
    if (const auto hash = raw.find('#'); hash != std::string::npos) raw.erase(hash);
    std::istringstream words(raw);
    std::vector<std::string> w;
    for (std::string word; words >> word;) w.push_back(word);
    if (w.empty()) continue;

    TimelineEvent e;
    e.line = line;
    if (!parse_double(w[0], e.time_s) || e.time_s < 0)
      fail(file, line, "time: '" + w[0] + "' is not a time in seconds >= 0");
    if (e.time_s < last_time)
      fail(file, line, "time: " + w[0] + " s is earlier than the line before");
    last_time = e.time_s;
    if (w.size() < 2) fail(file, line, "expected 'time control value' or 'time @directive'");
    const std::string& what = w[1];

    if (what[0] == '@') {
      const auto want_args = [&](std::size_t n) {
        if (w.size() != 2 + n)
          fail(file, line, what + ": expects " + std::to_string(n) + " argument(s)");
      };
      if (what == "@silent") { want_args(0); e.kind = TimelineEvent::Kind::Silent; }
      else if (what == "@resume") { want_args(0); e.kind = TimelineEvent::Kind::Resume; }
      else if (what == "@end") { want_args(0); e.kind = TimelineEvent::Kind::End; }
      else if (what == "@status") {
        want_args(1);
        e.kind = TimelineEvent::Kind::Status;
        e.status = parse_status(file, line, w[2]);
      } else if (what == "@corrupt") {
        want_args(1);
        e.kind = TimelineEvent::Kind::Corrupt;
        double n = 0;
        if (!parse_double(w[2], n) || n < 1 || n > 1e6 || n != std::floor(n))
          fail(file, line, "@corrupt: '" + w[2] + "' is not a frame count >= 1");
        e.count = static_cast<int>(n);
      } else if (what == "@invalid") {
        want_args(1);
        e.kind = TimelineEvent::Kind::Invalid;
        const auto c = definition.find_control(w[2]);
        if (!c) fail(file, line, "@invalid: unknown control '" + w[2] + "'");
        if (definition.controls[*c].kind == ControlKind::Button)
          fail(file, line, "@invalid: a button has no 'not available' value");
        e.control = *c;
      } else {
        fail(file, line, "unknown directive '" + what +
                             "' (@silent, @resume, @status, @corrupt, @invalid, @end)");
      }
      timeline.events.push_back(e);
      continue;
    }

    const auto c = definition.find_control(what);
    if (!c) fail(file, line, "unknown control '" + what + "' (not in " + definition.file + ")");
    if (w.size() != 3) fail(file, line, what + ": expected one value");
    e.control = *c;
    const ControlDefinition& control = definition.controls[*c];
    const std::string& value = w[2];
    switch (control.kind) {
      case ControlKind::Axis: {
        double v = 0;
        if (!parse_double(value, v) || v < -1.0 || v > 1.0)
          fail(file, line, what + ": '" + value + "' is not an axis value in -1..1");
        e.axis = static_cast<float>(v);
        break;
      }
      case ControlKind::Button:
        if (value == "1" || value == "pressed" || value == "true" || value == "on") e.pressed = true;
        else if (value == "0" || value == "released" || value == "false" || value == "off") e.pressed = false;
        else fail(file, line, what + ": '" + value + "' is not pressed/released (1/0)");
        break;
      case ControlKind::Switch: {
        const auto it = std::find(control.positions.begin(), control.positions.end(), value);
        double index = -1;
        if (it != control.positions.end()) {
          e.position = static_cast<uint8_t>(it - control.positions.begin());
        } else if (parse_double(value, index) && index >= 0 && index < static_cast<double>(control.positions.size()) &&
                   index == std::floor(index)) {
          e.position = static_cast<uint8_t>(index);
        } else {
          fail(file, line, what + ": '" + value + "' is not one of its positions");
        }
        break;
      }
    }
    timeline.events.push_back(e);
  }
  return timeline;
}

Timeline load_timeline(const std::string& path, const PanelDefinition& definition) {
  return parse_timeline(read_text_file(path), path, definition);
}

}  // namespace rise::panels
