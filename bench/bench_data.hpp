#pragma once

// The benchmarks' input files: the shared test data (RISE_TEST_DATA, default
// ../shared/data beside the project) or a path given on the command line.

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

namespace rise::bench {

/// `given` when not empty, else RISE_TEST_DATA/`relative`; nullopt (with a
/// message on stderr) when the file is absent.
inline std::optional<std::string> data_file(const char* given, const std::string& relative) {
  const char* root = std::getenv("RISE_TEST_DATA");
  const std::string data = root ? root : std::string(RISE_SOURCE_DIR) + "/../shared/data";
  const std::string path = given && given[0] ? given : data + "/" + relative;
  if (std::filesystem::exists(path)) return path;
  std::fprintf(stderr, "%s is absent (set RISE_TEST_DATA)\n", path.c_str());
  return std::nullopt;
}

}  // namespace rise::bench
