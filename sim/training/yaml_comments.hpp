#pragma once

// The comments of a YAML file the builders keep when they write it again
// (sim/training/training_writer.hpp, task_writer.hpp): the `# ...` ending an
// entry's line, and the comment lines that open the file. yaml-cpp drops
// comments; these read them from the text by line. Pure.

#include <string>

namespace rise::sim::training {

/// Line `line` (1-based) of `text` ("" past its end).
std::string line_text(const std::string& text, int line);

/// The `# ...` that ends line `line`: a # after a blank, outside quotes
/// (YAML 1.2 section 6.6), without the # and the blanks around it; control
/// characters as blanks, so it is one line of text when written again.
std::string trailing_comment(const std::string& text, int line);

/// The comment lines that open the file, before its first key, without
/// their `# `, joined by line breaks.
std::string leading_comment(const std::string& text);

/// The writers' side: a YAML text built line by line, each entry with its
/// comment padded to a column, so that reading the comments back
/// (trailing_comment, leading_comment) gives what was written.
class CommentedLines {
 public:
  /// Appends `entry` and its comment; returns the entry's line (1-based).
  int add(const std::string& entry, const std::string& comment);
  /// The file's opening comment, one `# ` line per line of `comment`.
  void comment_block(const std::string& comment);
  const std::string& text() const { return text_; }

 private:
  std::string text_;
  int count_ = 0;
};

}  // namespace rise::sim::training
