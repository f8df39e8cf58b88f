#include "sim/training/yaml_comments.hpp"

#include <sstream>
#include <vector>

#include "panels/yaml_writer.hpp"

namespace rise::sim::training {

namespace {

// Without blanks at either end; control characters (a CR, a NUL) as blanks,
// so the comment is one line of text when written again.
std::string trim(std::string s) {
  for (char& c : s)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = ' ';
  const auto b = s.find_first_not_of(' ');
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(' ') - b + 1);
}

// A comment as the loader reads it back: control characters (line breaks
// too) as blanks, none at the end, and for one on an entry's line none at
// the start either; so writing is a fixed point.
std::string comment_text(std::string s, bool keep_leading) {
  for (char& c : s)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = ' ';
  const auto last = s.find_last_not_of(' ');
  if (last == std::string::npos) return "";
  s.erase(last + 1);
  if (!keep_leading) s.erase(0, s.find_first_not_of(' '));
  return s;
}

}  // namespace

// Line `line` (1-based) of `text`.
std::string line_text(const std::string& text, int line) {
  std::size_t begin = 0;
  for (int i = 1; i < line && begin != std::string::npos; ++i) {
    begin = text.find('\n', begin);
    if (begin != std::string::npos) ++begin;
  }
  if (begin == std::string::npos || begin > text.size()) return "";
  const std::size_t end = text.find('\n', begin);
  return text.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
}

// The `# ...` that ends line `line`: a # after a blank, outside quotes (YAML
// 1.2 section 6.6), without the # and the blanks around it.
std::string trailing_comment(const std::string& text, int line) {
  const std::string l = line_text(text, line);
  const std::size_t hash = panels::yaml_comment_start(l);
  return hash == std::string::npos ? "" : trim(l.substr(hash + 1));
}

// The comment lines that open the file, before its first key: what the file
// is about, kept when a builder writes it again.
std::string leading_comment(const std::string& text) {
  std::istringstream in(text);
  std::string line, out;
  while (std::getline(in, line)) {
    const std::string t = trim(line);
    if (t.empty()) continue;
    if (t[0] != '#') break;
    std::string body = t.substr(1);
    if (!body.empty() && body[0] == ' ') body.erase(0, 1);
    out += (out.empty() ? "" : "\n") + body;
  }
  // A blank last line (`#` alone, or one of control characters only) says
  // nothing, and a writer cannot give it back: it is not kept.
  while (!out.empty() && out.back() == '\n') out.pop_back();
  return out;
}

int CommentedLines::add(const std::string& entry, const std::string& comment) {
  std::string line = entry;
  const std::string text = comment_text(comment, false);
  if (!text.empty()) {
    if (line.size() < 60) line.append(60 - line.size(), ' ');
    line += "  # " + text;
  }
  text_ += line + "\n";
  return ++count_;
}

void CommentedLines::comment_block(const std::string& comment) {
  std::vector<std::string> lines;
  std::istringstream in(comment);
  for (std::string l; std::getline(in, l);) lines.push_back(comment_text(l, true));
  // Blank lines first or last are not written: leading_comment would not read them back.
  auto first = lines.begin(), last = lines.end();
  while (first != last && first->empty()) ++first;
  while (last != first && (last - 1)->empty()) --last;
  for (auto l = first; l != last; ++l) add(l->empty() ? "#" : "# " + *l, "");
}

}  // namespace rise::sim::training
