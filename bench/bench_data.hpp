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

/// Starts the peer's Python `script` (written to /tmp/NAME.py) under Debian's
/// /usr/bin/python3 with `args` (shell words, already quoted), its stdout
/// readable from the returned pipe (pclose it); nullptr if it cannot start.
inline FILE* start_python(const std::string& name, const std::string& script, const std::string& args) {
  const std::string py = "/tmp/" + name + ".py";
  FILE* s = std::fopen(py.c_str(), "w");
  if (!s) return nullptr;
  std::fputs(script.c_str(), s);
  std::fclose(s);
  return ::popen(("/usr/bin/python3 " + py + " " + args).c_str(), "r");
}

}  // namespace rise::bench
