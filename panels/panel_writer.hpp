#pragma once

// The controls of a panel definition as the Console Builder edits them
// (instructor/console_builder.hpp), and the text they are written back into.
// Only the `controls:` list is rewritten, one flow mapping per control with
// the comment lines above it; every other line of the file (sources,
// feedback, their comments) is kept as it was, so a load → save keeps the
// definition's meaning (tests/panels/panel_writer_test.cpp checks it over
// every shipped definition through the loader, panel_definition.hpp).

#include <string>
#include <utility>
#include <vector>

namespace rise::panels {

/// A control's value as YAML holds it: a scalar (its text, as the loader
/// reads it) or a list of values (range, bits, positions).
struct FieldValue {
  bool list = false;
  std::string scalar;
  std::vector<FieldValue> items;
};

/// One entry of `controls:`: its keys in their order and the comment lines
/// above it (without '#', one per line, "" = none).
struct ControlEntry {
  std::string comment;
  std::vector<std::pair<std::string, FieldValue>> fields;
  int line = 0;  ///< where it starts in the text it was read from (1-based)

  /// The value of `key`, or nullptr.
  const FieldValue* find(const std::string& key) const;
};

/// The `controls:` list of a definition's text, unvalidated (the loader
/// judges it). Throws std::runtime_error "file:line: ..." for text that is
/// no YAML mapping or whose controls are no list of mappings.
std::vector<ControlEntry> read_panel_controls(const std::string& text, const std::string& file);

/// `text` with its `controls:` block (the top-level key and the lines up
/// to the next top-level key, less the comments and blank lines just above
/// that key) replaced by `controls` (appended when there is none). `lines`,
/// when given, gets each control's line in the result (1-based).
std::string write_panel_controls(const std::string& text, const std::vector<ControlEntry>& controls,
                                 std::vector<int>* lines = nullptr);

}  // namespace rise::panels
