#pragma once

// What the five builders' fuzz targets share (tests/fuzz/*_builder_fuzz.cpp):
// the page's body parsed as the server parses it, a shipped file's text, and
// the check every builder's errors pass: a message, and a line inside the
// YAML written.

#include <json/json.h>

#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include "tests/fuzz/fuzz_check.hpp"

namespace rise::fuzz {

/// `text` as JSON into *body; false when it is not JSON.
inline bool parse_json(const std::string& text, Json::Value* body) {
  std::string error;
  const std::unique_ptr<Json::CharReader> reader(Json::CharReaderBuilder().newCharReader());
  return reader->parse(text.data(), text.data() + text.size(), body, &error);
}

/// The whole of file `path` ("" when it cannot be read).
inline std::string file_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline int line_count(const std::string& text) {
  int n = 0;
  for (const char c : text) n += c == '\n';
  return n;
}

/// Every error has a message; those of file `file` ("": all) a line of `yaml` (0: none).
template <typename Errors>
void check_builder_errors(const Errors& errors, const std::string& yaml, const std::string& file = "") {
  for (const auto& e : errors) {
    fuzz_check(!e.message.empty());
    if (file.empty() || e.file == file) fuzz_check(e.line >= 0 && e.line <= line_count(yaml) + 1);
  }
}

}  // namespace rise::fuzz
