#include "panels/yaml_writer.hpp"

#include <cctype>
#include <cstdio>
#include <cstring>

namespace rise::panels {

namespace {

bool reserved_word(const std::string& s) {
  // Words YAML reads as something else than a string.
  static const char* const kReserved[] = {"true", "false", "yes", "no", "on", "off", "null", "y", "n", "nan", "inf"};
  std::string lower;
  for (const char ch : s) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  for (const char* r : kReserved)
    if (lower == r) return true;
  return false;
}

bool plain_word(const std::string& s, const char* also) {
  if (s.empty()) return false;
  if (!(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  for (const char ch : s) {
    const bool word = std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '.' || ch == '-';
    if (!word && (ch == 0 || std::strchr(also, ch) == nullptr)) return false;
  }
  return !reserved_word(s);
}

}  // namespace

std::string yaml_double_quoted(const std::string& text) {
  std::string out = "\"";
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (ch == '"' || ch == '\\') {
      out += '\\';
      out += ch;
    } else if (ch == '\n') {
      out += "\\n";
    } else if (c < 0x20 || c == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    } else {
      out += ch;
    }
  }
  return out + "\"";
}

std::string yaml_string(const std::string& text, const char* also) {
  return plain_word(text, also) ? text : yaml_double_quoted(text);
}

std::size_t yaml_comment_start(const std::string& line) {
  char quote = 0;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quote) {
      if (c == quote) quote = 0;
      else if (c == '\\' && quote == '"') ++i;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '#' && (i == 0 || line[i - 1] == ' ' || line[i - 1] == '\t')) {
      return i;
    }
  }
  return std::string::npos;
}

}  // namespace rise::panels
