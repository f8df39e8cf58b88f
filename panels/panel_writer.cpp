#include "panels/panel_writer.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <sstream>
#include <stdexcept>

namespace rise::panels {

namespace {

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

bool is_comment(const std::string& line) {
  const auto first = line.find_first_not_of(" \t");
  return first != std::string::npos && line[first] == '#';
}

bool is_blank(const std::string& line) { return line.find_first_not_of(" \t\r") == std::string::npos; }

// A line that starts a top-level key (or a document marker).
bool is_top_level(const std::string& line) {
  return !line.empty() && line[0] != ' ' && line[0] != '\t' && line[0] != '#' && !is_blank(line);
}

FieldValue field_of(const YAML::Node& node, const std::string& where, const std::string& file) {
  FieldValue v;
  if (node.IsSequence()) {
    v.list = true;
    for (const auto& item : node) v.items.push_back(field_of(item, where, file));
  } else if (node.IsScalar()) {
    v.scalar = node.Scalar();
  } else if (!node.IsNull()) {
    throw std::runtime_error(file + ":" + std::to_string(node.Mark().line + 1) + ": " + where +
                             ": a value or a list, not a mapping");
  }
  return v;
}

// The comment lines right above line `line` (1-based), '#' and one space taken off.
std::string comment_above(const std::vector<std::string>& lines, int line) {
  std::vector<std::string> found;
  for (int i = line - 2; i >= 0 && is_comment(lines[static_cast<std::size_t>(i)]); --i) {
    std::string c = lines[static_cast<std::size_t>(i)];
    c = c.substr(c.find('#') + 1);
    if (!c.empty() && c[0] == ' ') c.erase(0, 1);
    found.push_back(c);
  }
  std::string out;
  for (auto it = found.rbegin(); it != found.rend(); ++it) out += (out.empty() ? "" : "\n") + *it;
  return out;
}

void emit(YAML::Emitter& out, const FieldValue& v) {
  if (!v.list) {
    out << v.scalar;
    return;
  }
  out << YAML::Flow << YAML::BeginSeq;
  for (const auto& item : v.items) emit(out, item);
  out << YAML::EndSeq;
}

std::string control_line(const ControlEntry& c) {
  YAML::Emitter out;
  out << YAML::Flow << YAML::BeginMap;
  for (const auto& [key, value] : c.fields) {
    out << YAML::Key << key << YAML::Value;
    emit(out, value);
  }
  out << YAML::EndMap;
  return std::string("  - ") + out.c_str();
}

// [begin, end) of the controls block's lines; begin == end == size when none.
std::pair<std::size_t, std::size_t> controls_block(const std::vector<std::string>& lines) {
  std::size_t begin = 0;
  while (begin < lines.size() && lines[begin].rfind("controls:", 0) != 0) ++begin;
  if (begin == lines.size()) return {begin, begin};
  std::size_t end = begin + 1;
  while (end < lines.size() && !is_top_level(lines[end])) ++end;
  // The comments and blank lines right above the next key are that key's.
  while (end > begin + 1 && (is_comment(lines[end - 1]) || is_blank(lines[end - 1])) && end < lines.size()) --end;
  // ...and a trailing blank line at the end of the file stays too.
  while (end == lines.size() && end > begin + 1 && is_blank(lines[end - 1])) --end;
  return {begin, end};
}

}  // namespace

const FieldValue* ControlEntry::find(const std::string& key) const {
  for (const auto& [k, v] : fields)
    if (k == key) return &v;
  return nullptr;
}

std::vector<ControlEntry> read_panel_controls(const std::string& text, const std::string& file) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(file + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  if (!root.IsMap()) throw std::runtime_error(file + ":1: expected a mapping (panel:, sources:, controls:)");
  const std::vector<std::string> lines = split_lines(text);
  std::vector<ControlEntry> controls;
  const YAML::Node list = root["controls"];
  if (!list) return controls;
  if (!list.IsSequence())
    throw std::runtime_error(file + ":" + std::to_string(list.Mark().line + 1) + ": controls: expected a list");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const YAML::Node node = list[i];
    const std::string where = "controls[" + std::to_string(i) + "]";
    if (!node.IsMap())
      throw std::runtime_error(file + ":" + std::to_string(node.Mark().line + 1) + ": " + where + ": expected a mapping");
    ControlEntry c;
    c.line = node.Mark().line + 1;
    c.comment = comment_above(lines, c.line);
    for (const auto& kv : node) c.fields.emplace_back(kv.first.Scalar(), field_of(kv.second, where, file));
    controls.push_back(std::move(c));
  }
  return controls;
}

std::string write_panel_controls(const std::string& text, const std::vector<ControlEntry>& controls,
                                 std::vector<int>* lines_out) {
  const std::vector<std::string> lines = split_lines(text);
  auto [begin, end] = controls_block(lines);
  std::string out;
  int line = 0;
  auto put = [&](const std::string& l) {
    out += l + "\n";
    ++line;
  };
  for (std::size_t i = 0; i < begin; ++i) put(lines[i]);
  if (begin == lines.size() && !lines.empty() && !is_blank(lines.back())) put("");
  if (lines_out) lines_out->clear();
  put("controls:");
  for (const auto& c : controls) {
    if (!c.comment.empty()) {
      std::istringstream comment(c.comment);
      std::string l;
      while (std::getline(comment, l)) {
        // A carriage return would end the comment for YAML and start a line of the file's.
        std::replace(l.begin(), l.end(), '\r', ' ');
        put("  #" + (l.empty() ? "" : " " + l));
      }
    }
    put(control_line(c));
    if (lines_out) lines_out->push_back(line);
  }
  for (std::size_t i = end; i < lines.size(); ++i) put(lines[i]);
  return out;
}

}  // namespace rise::panels
