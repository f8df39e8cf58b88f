#include "panels/yaml_reader.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace rise::panels {

// A control character of the file's text (a key, a value quoted in the
// message) as \xNN: an error stays one "file:line: ..." line (a key holding a
// line break split it; found by the training_graph fuzz target).
std::string printable(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (static_cast<unsigned char>(c) >= 0x20 && c != 0x7f) {
      out += c;
      continue;
    }
    char hex[8];
    std::snprintf(hex, sizeof hex, "\\x%02x", static_cast<unsigned>(static_cast<unsigned char>(c)));
    out += hex;
  }
  return out;
}


void YamlReader::fail(const YAML::Node& node, const std::string& key, const std::string& what) const {
  const int line = node.IsDefined() && node.Mark().line >= 0 ? node.Mark().line + 1 : 0;
  throw std::runtime_error(file_ + ":" + std::to_string(line) + ": " + printable((key.empty() ? "" : key + ": ") + what));
}

void YamlReader::only_keys(const YAML::Node& map, const std::string& where,
                           std::initializer_list<const char*> allowed) const {
  if (!map.IsMap()) fail(map, where, "expected a mapping");
  for (const auto& kv : map) {
    if (!kv.first.IsScalar()) fail(kv.first, where, "a key must be a name, not a list or mapping");
    const auto key = kv.first.Scalar();
    bool ok = false;
    for (const char* a : allowed) ok = ok || key == a;
    if (!ok) fail(kv.first, join(where, key), "unknown key");
  }
}

double YamlReader::positive(const YAML::Node& map, const char* key, const std::string& where, double fallback,
                            bool allow_zero) const {
  const YAML::Node n = map[key];
  if (!n) return fallback;
  const std::string k = where + "." + key;
  const double v = as<double>(n, k);
  if (!(allow_zero ? v >= 0.0 : v > 0.0)) fail(n, k, allow_zero ? "must be >= 0" : "must be > 0");
  return v;
}

YAML::Node YamlReader::load_text(const std::string& text) const {
  try {
    return YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw std::runtime_error(file_ + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

const char* YamlReader::not_a_value() const {
  return wording_ == ValueWording::NameType ? "expected a value, not a list or mapping" : "expected a value";
}

std::string read_text_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string beside(const std::string& file, const std::string& path) {
  std::filesystem::path p(path);
  if (p.is_relative()) p = std::filesystem::path(file).parent_path() / p;
  return p.lexically_normal().string();
}

}  // namespace rise::panels
