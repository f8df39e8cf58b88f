#pragma once

// Reading YAML files with messages that name file:line and the key ("file:line: key: what"), so a
// user can jump to it. Panel definitions and the simulator's robot, world, task and scenario files
// read through it.

#include <yaml-cpp/yaml.h>

#include <array>
#include <initializer_list>
#include <string>
#include <type_traits>

namespace rise::panels {

/// How `as` words a value it cannot read: panel definitions name the type they expected
/// ("cannot read 'lots' as a number"), the simulator's files only quote the text.
enum class ValueWording { QuoteOnly, NameType };

/// `path` as a file named in `file` means it: a relative path is relative
/// to `file`'s folder (a panel definition's dbc:, eds:, sdl_db:).
std::string beside(const std::string& file, const std::string& path);

/// `text` with each control character as \xNN, so that an error quoting
/// the file's text stays on one line.
std::string printable(const std::string& text);

class YamlReader {
 public:
  explicit YamlReader(std::string file, ValueWording wording = ValueWording::QuoteOnly)
      : file_(std::move(file)), wording_(wording) {}

  /// The file named in every message (robot files resolve their URDF against it).
  const std::string& file() const { return file_; }

  /// Throws "file:line: key: what" (no "key: " when key is empty; line 0 when the node has none).
  [[noreturn]] void fail(const YAML::Node& node, const std::string& key, const std::string& what) const;

  /// Rejects keys not in `allowed`, so a typo never becomes a silent default.
  void only_keys(const YAML::Node& map, const std::string& where, std::initializer_list<const char*> allowed) const;

  /// map[key], or `fallback` when it is absent.
  template <typename T>
  T get(const YAML::Node& map, const char* key, const std::string& where, T fallback) const {
    const YAML::Node node = map[key];
    if (!node) return fallback;
    return as<T>(node, join(where, key));
  }

  /// map[key]; "missing" when it is absent.
  template <typename T>
  T require(const YAML::Node& map, const char* key, const std::string& where) const {
    const YAML::Node node = map[key];
    if (!node) fail(map, join(where, key), "missing");
    return as<T>(node, join(where, key));
  }

  template <typename T>
  T as(const YAML::Node& node, const std::string& key) const {
    if (!node.IsScalar()) fail(node, key, not_a_value());
    try {
      return node.as<T>();
    } catch (const YAML::Exception&) {
      fail(node, key, "cannot read '" + node.Scalar() + "'" + as_type<T>());
    }
  }

  /// A number > 0 (or >= 0 with allow_zero).
  double positive(const YAML::Node& map, const char* key, const std::string& where, double fallback,
                  bool allow_zero = false) const;

  /// The list of N numbers at map[key] (required).
  template <std::size_t N>
  std::array<double, N> vector(const YAML::Node& map, const char* key, const std::string& where) const {
    static const char* const kShapes[] = {"", "[x]", "[x, y]", "[x, y, z]"};
    const YAML::Node v = map[key];
    const std::string k = join(where, key);
    if (!v || !v.IsSequence() || v.size() != N) fail(v ? v : map, k, std::string("expected ") + kShapes[N]);
    std::array<double, N> out{};
    for (std::size_t i = 0; i < N; ++i) out[i] = as<double>(v[i], k);
    return out;
  }

  /// Parses `text`; a syntax error throws "file:line: <yaml-cpp's message>".
  YAML::Node load_text(const std::string& text) const;

  /// "a.b", or "b" when a is empty.
  static std::string join(const std::string& a, const std::string& b) { return a.empty() ? b : a + "." + b; }

 private:
  const char* not_a_value() const;

  template <typename T>
  std::string as_type() const {
    if (wording_ == ValueWording::QuoteOnly) return "";
    if constexpr (std::is_same_v<T, bool>) return " as true/false";
    else if constexpr (std::is_integral_v<T>) return " as an integer";
    else if constexpr (std::is_floating_point_v<T>) return " as a number";
    else return " as text";
  }

  std::string file_;
  ValueWording wording_;
};

/// Reads a whole file; throws "path: cannot open: <strerror>" when it cannot.
std::string read_text_file(const std::string& path);

}  // namespace rise::panels
