#pragma once

// The YAML writers' one way to write a string (panels/, sim/world_writer,
// sim/yaml_edit, sim/training's writers): plain where YAML reads it back as
// the same string, else double-quoted; and where a `# comment` starts on a
// line. Pure; the reading side is yaml_reader.hpp.

#include <string>

namespace rise::panels {

/// `text` double-quoted: `"` and `\` escaped, a line break as \n, other
/// control characters as \xNN; reads back as `text` (in a flow collection too).
std::string yaml_double_quoted(const std::string& text);

/// `text` plain when it is a word YAML reads back as that string: a letter
/// or _ first, then letters, digits, _ . - and the characters of `also`
/// (e.g. "/" for paths), and no word YAML reads as something else (true,
/// null, nan, ...); else double-quoted.
std::string yaml_string(const std::string& text, const char* also = "");

/// Where the `#` of the comment on `line` is: at the start or after a blank,
/// outside quotes (YAML 1.2 section 6.6); npos when the line has none.
std::size_t yaml_comment_start(const std::string& line);

}  // namespace rise::panels
