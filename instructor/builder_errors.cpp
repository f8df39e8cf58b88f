#include "instructor/builder_errors.hpp"

#include <filesystem>
#include <regex>
#include <sstream>

namespace rise::instructor {

namespace fs = std::filesystem;

bool split_location(const std::string& text, std::string* file, int* line, std::string* rest) {
  static const std::regex re(R"(^(.+?):(\d{1,9}): (.*)$)");
  std::smatch m;
  if (!std::regex_match(text, m, re)) return false;
  *file = m[1];
  *line = std::stoi(m[2]);
  *rest = m[3];
  return true;
}

bool split_key(const std::string& text, std::string* key, std::string* message, bool dashes) {
  static const std::regex plain(R"(^([A-Za-z_][A-Za-z0-9_]*(\[\d+\])?(\.[A-Za-z_][A-Za-z0-9_]*(\[\d+\])?)*): (.*)$)");
  static const std::regex dashed(
      R"(^([A-Za-z_][A-Za-z0-9_\-]*(\[\d+\])?(\.[A-Za-z_][A-Za-z0-9_\-]*(\[\d+\])?)*): (.*)$)");
  std::smatch m;
  if (!std::regex_match(text, m, dashes ? dashed : plain)) return false;
  *key = m[1];
  *message = m[5];
  return true;
}

BuilderError loader_error(const std::string& text, const std::string& path, bool dashes) {
  BuilderError e;
  std::string file, rest;
  if (!split_location(text, &file, &e.line, &rest)) {
    e.file = fs::path(path).filename().string();
    e.message = text;
    return e;
  }
  e.file = fs::path(file).filename().string();
  if (!split_key(rest, &e.key, &e.message, dashes)) e.message = rest;
  return e;
}

std::vector<BuilderError> loader_errors(const std::string& what, const std::string& path, bool dashes) {
  std::vector<BuilderError> out;
  std::istringstream in(what);
  std::string line;
  while (std::getline(in, line))
    if (!line.empty()) out.push_back(loader_error(line, path, dashes));
  return out;
}

Json::Value builder_error_json(const BuilderError& e) {
  Json::Value j;
  j["file"] = e.file;
  j["line"] = e.line;
  j["key"] = e.key;
  j["message"] = e.message;
  return j;
}

Json::Value check_json(const std::string& yaml, const std::vector<BuilderError>& errors) {
  Json::Value v;
  v["yaml"] = yaml;
  v["ok"] = errors.empty();
  Json::Value list(Json::arrayValue);
  for (const auto& e : errors) list.append(builder_error_json(e));
  v["errors"] = list;
  return v;
}

}  // namespace rise::instructor
