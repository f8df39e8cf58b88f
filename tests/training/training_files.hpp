#pragma once

// Helpers for the training tests: paths in the source tree and task or
// training files written into a temporary folder.

#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace rise::test {

inline std::string src(const std::string& relative) { return std::string(RISE_SOURCE_DIR) + "/" + relative; }

/// A fresh folder under the temp dir, named after the test and the process.
inline std::string temp_dir(const std::string& name) {
  const auto d = std::filesystem::temp_directory_path() / ("rise-training-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d.string();
}

inline std::string write_file(const std::string& dir, const std::string& name, const std::string& text) {
  const auto p = (std::filesystem::path(dir) / name).string();
  std::ofstream(p) << text;
  return p;
}

inline std::string read_file(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// The header of a task file on the building world with the tracked robot
/// (or `robot`), absolute paths, the given start pose.
inline std::string task_header(const std::string& name, const std::string& start, double time_limit_s,
                               const std::string& script = "", const std::string& robot = "tracked_eod") {
  return "task: " + name + "\nrobot: " + src("sim/robots/" + robot + ".yaml") + "\nworld: " +
         src("sim/worlds/building.yaml") + "\npanel: " + src("panels/definitions/rise_console.yaml") + "\n" +
         (script.empty() ? "" : "console_script: " + script + "\n") + "start: " + start +
         "\ntime_limit_s: " + std::to_string(time_limit_s) + "\n";
}

}  // namespace rise::test
