#pragma once

// Edits a YAML file's scalars in place, in its text: what the Robot Builder
// saves (instructor/robot_builder.hpp). The robot files explain themselves in
// comments (units, why a value is what it is); a writer that rebuilt the
// file from the model would drop them or have to carry each one, so the
// page sends only the values it changed, and each is written over the
// scalar's own characters (yaml-cpp's Mark gives its offset), leaving every
// other byte — comments, order, flow or block style, alignment — as it was.
// A key the file lacks (an `invert` never written) is added to its mapping:
// inside a flow mapping `{...}` before the `}`, in a block mapping as a new
// line above its first key, with that key's indentation. Pure; throws on
// input it cannot apply, never on a value (the loader judges the values).

#include <stdexcept>
#include <string>
#include <vector>

namespace rise::sim {

/// A path names a value: mapping keys joined by '.', a list's item as
/// "[i]": "control.linear.max_mps", "control.speed_scale.values[2]",
/// "sensors.cameras[0].name".
struct YamlScalar {
  std::string path;
  std::string value;  ///< the scalar as yaml-cpp reads it
  int line = 0;       ///< 1-based
};

struct YamlEdit {
  std::string path;
  std::string value;  ///< written plain when it reads back the same, else double-quoted
};

/// An edit that cannot be applied: its path and why.
class YamlEditError : public std::runtime_error {
 public:
  /// what(): "path: what", the path's control characters as \xNN.
  YamlEditError(std::string path, const std::string& what);
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

constexpr std::size_t kMaxYamlEditText = 1 << 20;  ///< bytes of text an edit reads
constexpr std::size_t kMaxYamlEdits = 1000;

/// Every scalar of `text` whose path can be named (keys of letters, digits,
/// _ and -), in document order. Throws std::runtime_error "line: reason"
/// for text that is not YAML.
std::vector<YamlScalar> yaml_scalars(const std::string& text);

/// `text` with each edit applied in turn. Throws YamlEditError for a path
/// that is malformed, runs through a scalar or past a list's end, names a
/// mapping or list, or a value that cannot be rewritten in place (a
/// multi-line or aliased scalar); nothing is returned then.
std::string apply_yaml_edits(const std::string& text, const std::vector<YamlEdit>& edits);

/// `value` as one YAML scalar that reads back as `value` (in a flow
/// collection too): plain when it is safe, else double-quoted.
std::string yaml_flow_scalar(const std::string& value);

}  // namespace rise::sim
