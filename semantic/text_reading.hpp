#pragma once

// Reading text file formats: a whole file, its lines with their numbers,
// a line's words, and numbers parsed locale-independently, with errors
// that name the file and the line ("path:line: message") or the byte
// offset ("path: byte N: message"). Shared by semantic/'s readers and
// sim/'s PCD reader; it needs only the standard library.

#include <algorithm>
#include <charconv>
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace rise::semantic::formats {

std::string read_file(const std::string& path);  ///< throws "path: cannot open: <strerror>"
[[noreturn]] void fail_line(const std::string& path, size_t line, const std::string& message);
[[noreturn]] void fail_byte(const std::string& path, size_t byte, const std::string& message);

/// The whitespace-separated words of a line.
std::vector<std::string_view> words(std::string_view line);

/// from_chars over the whole of `s` (a leading '+' allowed); false if any is left.
template <typename T>
bool parse(std::string_view s, T& v) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc{} && p == s.data() + s.size();
}

/// `s` as a number, else "path:line: what: not a number: 's'".
template <typename T>
T number(std::string_view s, const std::string& path, size_t line, std::string_view what) {
  T v{};
  if (!parse(s, v)) fail_line(path, line, std::string(what) + ": not a number: '" + std::string(s) + "'");
  return v;
}

/// Text split into lines with their 1-based numbers; '\r' dropped. `pos` is
/// the first byte after the last line returned (where binary data starts).
struct Lines {
  std::string_view text;
  size_t pos = 0;
  size_t number = 0;
  bool next(std::string_view& line) {
    if (pos >= text.size()) return false;
    const size_t end = std::min(text.find('\n', pos), text.size());
    line = text.substr(pos, end - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos = end + 1;
    ++number;
    return true;
  }
};

}  // namespace rise::semantic::formats
