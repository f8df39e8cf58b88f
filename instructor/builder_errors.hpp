#pragma once

// The builders' errors as the pages show them: a loader's message
// ("file:line: key: message", panels/yaml_reader.hpp) taken apart into file,
// line, key and message, and a check's {yaml, ok, errors} JSON. Pure; no
// server (the fuzz targets link it).

#include <json/json.h>

#include <string>
#include <vector>

#include "instructor/design_files.hpp"

namespace rise::instructor {

/// "file:line: rest" → file, line, rest; false when the text has no such start.
bool split_location(const std::string& text, std::string* file, int* line, std::string* rest);

/// "key: message" → key, message when the text starts with a key path
/// ("transitions[3].if", letters, digits and _; with `dashes` '-' too, as
/// URDF names have); false otherwise.
bool split_key(const std::string& text, std::string* key, std::string* message, bool dashes = false);

/// One line of a loader's message as an error of file `path` (its name when
/// the text names no file; "": none).
BuilderError loader_error(const std::string& text, const std::string& path, bool dashes = false);

/// Each non-empty line of a loader's message (several errors at once), as loader_error.
std::vector<BuilderError> loader_errors(const std::string& what, const std::string& path, bool dashes = false);

/// {file, line, key, message}.
Json::Value builder_error_json(const BuilderError& e);

/// {yaml, ok, errors}: what every builder's check answers.
Json::Value check_json(const std::string& yaml, const std::vector<BuilderError>& errors);

}  // namespace rise::instructor
