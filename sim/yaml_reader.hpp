#pragma once

// Reading YAML files with messages that name file:line and the key.

#include <yaml-cpp/yaml.h>

#include <array>
#include <initializer_list>
#include <stdexcept>
#include <string>

namespace rise::sim {

class YamlReader {
 public:
  explicit YamlReader(std::string file) : file_(std::move(file)) {}

  /// The file named in every message (robot files resolve their URDF against it).
  const std::string& file() const { return file_; }

  [[noreturn]] void fail(const YAML::Node& node, const std::string& key, const std::string& what) const {
    const int line = node.IsDefined() ? node.Mark().line + 1 : 0;
    throw std::runtime_error(file_ + ":" + std::to_string(line) + ": " + (key.empty() ? "" : key + ": ") + what);
  }

  /// Rejects keys not in `allowed`, so a typo never becomes a silent default.
  void only_keys(const YAML::Node& map, const std::string& where, std::initializer_list<const char*> allowed) const {
    if (!map.IsMap()) fail(map, where, "expected a mapping");
    for (const auto& kv : map) {
      const auto key = kv.first.as<std::string>();
      bool ok = false;
      for (const char* a : allowed) ok = ok || key == a;
      if (!ok) fail(kv.first, where.empty() ? key : where + "." + key, "unknown key");
    }
  }

  template <typename T>
  T as(const YAML::Node& node, const std::string& key) const {
    if (!node.IsScalar()) fail(node, key, "expected a value");
    try {
      return node.as<T>();
    } catch (const YAML::Exception&) {
      fail(node, key, "cannot read '" + node.Scalar() + "'");
    }
  }

  /// A number > 0 (or >= 0 with allow_zero).
  double positive(const YAML::Node& map, const char* key, const std::string& where, double fallback,
                  bool allow_zero = false) const {
    const YAML::Node n = map[key];
    if (!n) return fallback;
    const std::string k = where + "." + key;
    const double v = as<double>(n, k);
    if (!(allow_zero ? v >= 0.0 : v > 0.0)) fail(n, k, allow_zero ? "must be >= 0" : "must be > 0");
    return v;
  }

  /// The list of N numbers at map[key] (required).
  template <std::size_t N>
  std::array<double, N> vector(const YAML::Node& map, const char* key, const std::string& where) const {
    static const char* const kShapes[] = {"", "[x]", "[x, y]", "[x, y, z]"};
    const YAML::Node v = map[key];
    const std::string k = where.empty() ? key : where + "." + key;
    if (!v || !v.IsSequence() || v.size() != N) fail(v ? v : map, k, std::string("expected ") + kShapes[N]);
    std::array<double, N> out{};
    for (std::size_t i = 0; i < N; ++i) out[i] = as<double>(v[i], k);
    return out;
  }

  YAML::Node load_text(const std::string& text) const {
    try {
      return YAML::Load(text);
    } catch (const YAML::ParserException& e) {
      throw std::runtime_error(file_ + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
    }
  }

 private:
  std::string file_;
};

/// Reads a whole file; throws "path: cannot open: <strerror>" when it cannot.
std::string read_text_file(const std::string& path);

}  // namespace rise::sim
