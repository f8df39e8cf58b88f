#include "sim/yaml_edit.hpp"

#include <yaml-cpp/yaml.h>

#include <cctype>
#include <cstdio>
#include <optional>

#include "panels/yaml_reader.hpp"
#include "panels/yaml_writer.hpp"

namespace rise::sim {

YamlEditError::YamlEditError(std::string path, const std::string& what)
    : std::runtime_error(panels::printable(path) + ": " + what), path_(std::move(path)) {}

namespace {

// One step of a path: a mapping key, or a list index when key is empty.
struct Step {
  std::string key;
  std::size_t index = 0;
};

bool key_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-'; }

bool valid_key(const std::string& k) {
  if (k.empty() || k.size() > 128) return false;
  for (char c : k)
    if (!key_char(c)) return false;
  return true;
}

std::vector<Step> parse_path(const std::string& path) {
  if (path.empty() || path.size() > 1000) throw YamlEditError(path, "expected a path like control.linear.max_mps");
  std::vector<Step> steps;
  std::size_t i = 0;
  while (i < path.size()) {
    if (path[i] == '[') {
      const std::size_t close = path.find(']', i);
      const std::string digits = path.substr(i + 1, close == std::string::npos ? 0 : close - i - 1);
      if (close == std::string::npos || digits.empty() || digits.size() > 6 ||
          digits.find_first_not_of("0123456789") != std::string::npos)
        throw YamlEditError(path, "expected [index] of a list");
      steps.push_back({"", std::stoul(digits)});
      i = close + 1;
      if (i < path.size() && path[i] == '.') ++i;
      continue;
    }
    std::size_t end = i;
    while (end < path.size() && key_char(path[end])) ++end;
    if (end == i) throw YamlEditError(path, "expected a key (letters, digits, _ -) at '" + path.substr(i, 20) + "'");
    steps.push_back({path.substr(i, end - i), 0});
    i = end;
    if (i < path.size() && path[i] == '.') {
      if (++i == path.size()) throw YamlEditError(path, "ends in '.'");
    } else if (i < path.size() && path[i] != '[') {
      throw YamlEditError(path, "expected '.' or '[' after a key");
    }
  }
  return steps;
}

YAML::Node load(const std::string& text) {
  if (text.size() > kMaxYamlEditText) throw std::runtime_error("the text is larger than 1 MiB");
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

// The value a mapping holds at `key` and the key's node, or nullopt.
std::optional<std::pair<YAML::Node, YAML::Node>> find_key(const YAML::Node& map, const std::string& key) {
  for (const auto& kv : map)
    if (kv.first.IsScalar() && kv.first.Scalar() == key) return std::make_pair(kv.first, kv.second);
  return std::nullopt;
}

std::size_t mark_pos(const YAML::Node& n, const std::string& text) {
  const int pos = n.Mark().pos;
  return pos >= 0 && static_cast<std::size_t>(pos) < text.size() ? static_cast<std::size_t>(pos) : std::string::npos;
}

// One past the quote that closes the quoted scalar opening at `pos`, or npos.
std::size_t quote_end(const std::string& text, std::size_t pos) {
  const char q = text[pos];
  for (std::size_t i = pos + 1; i < text.size(); ++i) {
    if (q == '"' && text[i] == '\\') ++i;
    else if (text[i] == q && q == '\'' && i + 1 < text.size() && text[i + 1] == '\'') ++i;
    else if (text[i] == q) return i + 1;
  }
  return std::string::npos;
}

// Where the scalar's characters end (one past), or npos when it cannot be
// rewritten in place.
std::size_t scalar_end(const std::string& text, std::size_t pos, const YAML::Node& n) {
  if (text[pos] == '"' || text[pos] == '\'') return quote_end(text, pos);
  const std::string& s = n.Scalar();
  if (s.empty() || s.find('\n') != std::string::npos || text.compare(pos, s.size(), s) != 0) return std::string::npos;
  return pos + s.size();
}

// The flow mapping that opens at `open`: its closing `}` and the last
// character of its content before it (`open` when it is empty); npos when
// it does not close.
struct FlowEnd {
  std::size_t close = std::string::npos;
  std::size_t last = std::string::npos;
};

FlowEnd flow_end(const std::string& text, std::size_t open) {
  int depth = 0;
  std::size_t last = open;
  for (std::size_t i = open; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '"' || c == '\'') {
      i = quote_end(text, i);
      if (i == std::string::npos) return {};
      last = --i;
    } else if (c == '#' && i > 0 && std::isspace(static_cast<unsigned char>(text[i - 1]))) {
      i = text.find('\n', i);  // a comment is no content
      if (i == std::string::npos) return {};
    } else if (c == '{' || c == '[') {
      ++depth;
      if (i != open) last = i;
    } else if (c == '}' || c == ']') {
      if (--depth == 0) return c == '}' ? FlowEnd{i, last} : FlowEnd{};
      last = i;
    } else if (!std::isspace(static_cast<unsigned char>(c))) {
      last = i;
    }
  }
  return {};
}

// `rest` (the keys below a missing key) around `value`: {a: {b: value}}.
std::string nested_value(const std::vector<Step>& rest, const std::string& value, const std::string& path) {
  std::string v = yaml_flow_scalar(value);
  for (auto it = rest.rbegin(); it != rest.rend(); ++it) {
    if (it->key.empty()) throw YamlEditError(path, "cannot add an item to a list that is not there");
    v = "{" + it->key + ": " + v + "}";
  }
  return v;
}

// Adds `key: value` to `map` (which lacks it).
std::string insert_key(const std::string& text, const YAML::Node& map, const std::string& key,
                       const std::string& value, const std::string& path) {
  const std::size_t pos = mark_pos(map, text);
  if (pos == std::string::npos) throw YamlEditError(path, "cannot find the mapping in the text");
  if (text[pos] == '{') {
    const FlowEnd end = flow_end(text, pos);
    if (end.close == std::string::npos) throw YamlEditError(path, "cannot find the end of the mapping");
    const std::size_t at = end.last + 1;
    const char* comma = end.last == pos ? "" : text[end.last] == ',' ? " " : ", ";  // `{a: 1, }` too
    const std::string entry = comma + key + ": " + value;
    return text.substr(0, at) + entry + text.substr(at);
  }
  if (map.size() == 0) throw YamlEditError(path, "cannot add a key to an empty mapping");
  const std::size_t first = mark_pos(map.begin()->first, text);
  if (first == std::string::npos) throw YamlEditError(path, "cannot find the mapping in the text");
  const std::size_t line = text.rfind('\n', first) == std::string::npos ? 0 : text.rfind('\n', first) + 1;
  const std::string indent = text.substr(line, first - line);
  if (indent.find_first_not_of(' ') != std::string::npos)
    throw YamlEditError(path, "cannot add a key to a mapping that starts on a list item's line");
  return text.substr(0, line) + indent + key + ": " + value + "\n" + text.substr(line);
}

std::string canonical(const std::vector<Step>& steps) {
  std::string out;
  for (const auto& s : steps) {
    if (s.key.empty()) out += "[" + std::to_string(s.index) + "]";
    else out += (out.empty() ? "" : ".") + s.key;
  }
  return out;
}

std::string apply_one(const std::string& text, const YamlEdit& edit, const std::vector<Step>& steps) {
  YAML::Node node = load(text);
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const Step& s = steps[i];
    if (s.key.empty()) {
      if (!node.IsSequence()) throw YamlEditError(edit.path, "not a list before [" + std::to_string(s.index) + "]");
      if (s.index >= node.size()) throw YamlEditError(edit.path, "the list has " + std::to_string(node.size()) + " items");
      node = node[s.index];
      continue;
    }
    if (!node.IsMap()) throw YamlEditError(edit.path, "not a mapping before '" + s.key + "'");
    const auto found = find_key(node, s.key);
    if (!found) {
      const std::vector<Step> rest(steps.begin() + static_cast<std::ptrdiff_t>(i) + 1, steps.end());
      return insert_key(text, node, s.key, nested_value(rest, edit.value, edit.path), edit.path);
    }
    node = found->second;
  }
  if (!node.IsScalar()) throw YamlEditError(edit.path, "is a mapping or a list, not a value");
  const std::size_t pos = mark_pos(node, text);
  const std::size_t end = pos == std::string::npos ? pos : scalar_end(text, pos, node);
  if (end == std::string::npos) throw YamlEditError(edit.path, "this value cannot be rewritten in place");
  return text.substr(0, pos) + yaml_flow_scalar(edit.value) + text.substr(end);
}

void collect(const YAML::Node& n, const std::string& path, std::vector<YamlScalar>& out) {
  if (n.IsScalar()) {
    if (!path.empty()) out.push_back({path, n.Scalar(), n.Mark().line + 1});
  } else if (n.IsSequence()) {
    for (std::size_t i = 0; i < n.size(); ++i) collect(n[i], path + "[" + std::to_string(i) + "]", out);
  } else if (n.IsMap()) {
    for (const auto& kv : n)
      if (kv.first.IsScalar() && valid_key(kv.first.Scalar()))
        collect(kv.second, path.empty() ? kv.first.Scalar() : path + "." + kv.first.Scalar(), out);
  }
}

bool plain_safe(const std::string& s) {
  if (s.empty() || s.size() > 200) return false;
  const auto c0 = static_cast<unsigned char>(s[0]);
  if (!(std::isalnum(c0) || s[0] == '_' || s[0] == '.' || (s[0] == '-' && s.size() > 1 && s[1] != ' '))) return false;
  for (const char ch : s)
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '.' || ch == '-' || ch == '+')) return false;
  return true;
}

}  // namespace

std::string yaml_flow_scalar(const std::string& value) {
  return plain_safe(value) ? value : panels::yaml_double_quoted(value);
}

std::vector<YamlScalar> yaml_scalars(const std::string& text) {
  std::vector<YamlScalar> out;
  collect(load(text), "", out);
  return out;
}

namespace {

// Every value but `path`'s, in document order.
std::vector<std::pair<std::string, std::string>> others(const std::vector<YamlScalar>& scalars, const std::string& path) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& s : scalars)
    if (s.path != path) out.emplace_back(s.path, s.value);
  return out;
}

// The edit, checked on the text it gives: the value at the path reads back
// as given and every other value is as it was (else nothing is written:
// YAML this editor does not foresee is refused, never changed otherwise).
std::string apply_checked(const std::string& text, const YamlEdit& edit) {
  const std::vector<Step> steps = parse_path(edit.path);
  const std::string path = canonical(steps);
  const std::vector<YamlScalar> before = yaml_scalars(text);
  const std::string out = apply_one(text, edit, steps);
  std::vector<YamlScalar> after;
  try {
    after = yaml_scalars(out);
  } catch (const std::exception&) {
    throw YamlEditError(edit.path, "cannot be written in place: the file would not be YAML");
  }
  int found = 0;
  for (const auto& s : after)
    if (s.path == path) found += s.value == edit.value ? 1 : 2;
  if (found != 1 || others(before, path) != others(after, path))
    throw YamlEditError(edit.path, "cannot be written in place here");
  return out;
}

}  // namespace

std::string apply_yaml_edits(const std::string& text, const std::vector<YamlEdit>& edits) {
  if (edits.size() > kMaxYamlEdits) throw YamlEditError("", "more than 1000 edits");
  std::string out = text;
  for (const auto& e : edits) {
    if (e.value.size() > 10000) throw YamlEditError(e.path, "a value longer than 10000 characters");
    out = apply_checked(out, e);
  }
  if (out.size() > kMaxYamlEditText) throw YamlEditError("", "the text would be larger than 1 MiB");
  return out;
}

}  // namespace rise::sim
