#pragma once

// What the browser tests share (browser_test.cpp and the builders' tests):
// the paths, whether a browser can run here, the RESULT line a check script
// printed, the builder server in a scratch folder, and the CLI programs' runs.

#include <json/json.h>
#include <httplib.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "msgs/clock.hpp"
#include "process/child_process.hpp"
#include "tests/process_support.hpp"
#include "web_peer.hpp"

namespace rise::instructor_test {

namespace fs = std::filesystem;

inline const std::string kSource = RISE_SOURCE_DIR;
inline const std::string kBin = std::string(RISE_BINARY_DIR) + "/bin";
inline const std::string kWeb = kSource + "/instructor/web";

/// Why the browser checks cannot run here, or "".
inline std::string missing_browser() {
  if (!fs::exists("/usr/bin/node")) return "node is not installed (/usr/bin/node)";
  const char* chromium = std::getenv("RISE_CHROMIUM");
  if (!fs::exists(chromium ? chromium : "/usr/bin/chromium")) return "chromium is not installed (/usr/bin/chromium)";
  if (!fs::exists(kWeb + "/node_modules/playwright-core")) return "playwright-core is not installed (npm ci in instructor/web)";
  return "";
}

inline std::string text(const Json::Value& v) { return Json::writeString(Json::StreamWriterBuilder(), v); }

/// The RESULT line a check printed.
inline Json::Value read_result(const std::string& log) {
  std::ifstream in(log);
  std::string line;
  Json::Value result;
  while (std::getline(in, line))
    if (line.rfind("RESULT ", 0) == 0) result = parse_json(line.substr(7));
  return result;
}

using rise::test::read_file;

/// How many non-black pixels a PNG screenshot has is not checked here: the
/// page measures its canvases itself (variance, robot colour); the file must
/// exist and be a PNG of some size.
inline bool is_png(const std::string& path) {
  const std::string s = read_file(path);
  return s.size() > 2000 && s.compare(1, 3, "PNG") == 0;
}

/// `PROGRAM ARGS...` (a program of the build's bin/), waited for up to 20 s:
/// its exit code and its output (stdout and stderr).
inline std::pair<int, std::string> run_program(const fs::path& dir, std::vector<std::string> argv) {
  argv[0] = kBin + "/" + argv[0];
  const std::string log = (dir / ("run-" + std::to_string(rise::msgs::monotonic_us()) + ".log")).string();
  rise::process::ChildProcess child(argv, log);
  const int code = child.wait_for(20000);
  if (code < 0) child.stop();
  return {code, read_file(log)};
}

/// `rise-trainer check FILE [--walk R]...`: its exit code and output.
inline std::pair<int, std::string> trainer_check(const fs::path& dir, const std::string& file,
                                                 const std::vector<std::string>& walk) {
  std::vector<std::string> argv{"rise-trainer", "check", file};
  for (const auto& w : walk) argv.insert(argv.end(), {"--walk", w});
  return run_program(dir, argv);
}

/// `rise-instructor serve --designs DESIGNS` (and `extra` flags) on a free
/// port of loopback, its log in `dir`; waits for its start-up line, then
/// asks /api/builder/trainings with the token. `up` false: no line or no 200.
struct BuilderServer {
  std::string token = "builder-" + std::to_string(::getpid());
  int port = free_port();
  rise::process::ChildProcess process;
  bool up = false;

  BuilderServer(const fs::path& dir, const fs::path& designs, const std::vector<std::string>& extra = {}) {
    std::vector<std::string> argv{kBin + "/rise-instructor", "serve", "--listen", "127.0.0.1:" + std::to_string(port),
                                  "--token", token, "--lcm", kLcm, "--designs", designs.string()};
    argv.insert(argv.end(), extra.begin(), extra.end());
    process = rise::process::ChildProcess(argv, (dir / "server.log").string());
    // Its start-up line comes once it listens; then it must answer.
    if (!rise::test::wait_for_text((dir / "server.log").string(), "rise-instructor serve: http://", 20000)) return;
    httplib::Client http("127.0.0.1", port);
    auto r = http.Get("/api/builder/trainings", {{"X-Rise-Token", token}});
    up = r && r->status == 200;
  }
  std::string base() const { return "http://127.0.0.1:" + std::to_string(port); }
};

/// The folder the pages' screenshots go to (build/instructor_screens).
inline std::string screens_dir() {
  const std::string d = std::string(RISE_BINARY_DIR) + "/instructor_screens";
  fs::create_directories(d);
  return d;
}

}  // namespace rise::instructor_test
