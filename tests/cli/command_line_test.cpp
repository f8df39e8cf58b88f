// Runs every built program with a command line a new user could type: the
// version, a mistyped option, a missing file. README "Programs": exit 0 ok,
// 1 the program ran and the answer is no, 2 bad input.

#include <catch2/catch.hpp>

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "process/child_process.hpp"
#include "cli/version.hpp"

namespace {

namespace fs = std::filesystem;

struct Run {
  int status = -1;
  std::string output;  // stdout and stderr
};

Run run(const std::vector<std::string>& args) {
  const fs::path log = fs::temp_directory_path() / ("rise_cli_test_" + std::to_string(::getpid()) + ".log");
  fs::remove(log);
  std::vector<std::string> argv = args;
  argv[0] = std::string(RISE_BINARY_DIR) + "/bin/" + args[0];
  Run r;
  {
    rise::process::ChildProcess child(argv, log.string());
    r.status = child.wait_for(20000);
  }
  std::ifstream in(log);
  std::ostringstream text;
  text << in.rdbuf();
  r.output = text.str();
  fs::remove(log);
  return r;
}

const std::vector<std::string> kPrograms{"rise",       "rise-hild",     "rise-sim",        "rise-trainer",
                                         "rise-panel", "rise-semantic", "rise-instructor", "rise-sound"};

}  // namespace

TEST_CASE("every program prints its name and the build's version for --version and exits 0", "[cli]") {
  const std::string version = rise::cli::version();
  CHECK(version.rfind("0.1.0", 0) == 0);
  const std::string program = GENERATE_REF(from_range(kPrograms));
  INFO(program);
  const Run r = run({program, "--version"});
  CHECK(r.status == 0);
  CHECK(r.output == program + " " + version + "\n");
}

TEST_CASE("every program exits 0 for --help and lists --version there", "[cli]") {
  const std::string program = GENERATE_REF(from_range(kPrograms));
  INFO(program);
  const Run r = run({program, "--help"});
  CHECK(r.status == 0);
  CHECK_THAT(r.output, Catch::Contains("--version"));
}

TEST_CASE("every program exits 2 for an unknown option, a bad value or a missing argument", "[cli]") {
  const std::vector<std::string> args = GENERATE(values<std::vector<std::string>>({
      {"rise", "--no-such-option"},
      {"rise", "status", "--every", "x"},
      {"rise", "demo", "--timeout", "x"},
      {"rise-hild", "--no-such-option"},
      {"rise-hild", "--publish-hz", "0", "--source", "mem://x"},
      {"rise-hild", "dbc", "decode", "only_one.dbc"},
      {"rise-sim", "--no-such-option"},
      {"rise-sim", "--state-hz", "0"},
      {"rise-sim", "--scan-format", "jpeg"},
      {"rise-trainer", "--no-such-option"},
      {"rise-trainer", "check"},
      {"rise-trainer", "check", "sim/training/examples/fig10_training.yaml", "--walk", "scor=1"},
      {"rise-trainer", "check", "sim/training/examples/fig10_training.yaml", "--walk", "score=x"},
      {"rise-trainer", "check", "sim/training/examples/approach_object.yaml", "--walk", "score=1"},
      {"rise-panel", "--no-such-option"},
      {"rise-panel", "emulate", "--hid", "pad.rpt", "--hid-period-ms", "5000"},
      {"rise-semantic", "--no-such-option"},
      {"rise-semantic", "register", "a.pcd", "b.pcd", "--metric", "triangle"},
      {"rise-semantic", "register", "a.pcd", "b.pcd", "--min-dist", "1", "--max-dist", "0.5"},
      {"rise-instructor", "--no-such-option"},
      {"rise-instructor", "report", "--trainee", "t1"},
      {"rise-sound", "--no-such-option"},
      {"rise-sound", "--device", "null"},
      {"rise-sound", "--id", "t1", "--seconds", "-1"},
  }));
  std::string line;
  for (const auto& a : args) line += a + " ";
  INFO(line);
  const Run r = run(args);
  CHECK(r.status == 2);
  CHECK_FALSE(r.output.empty());
}

TEST_CASE("a missing file is named with the OS's reason, and the program exits 2", "[cli]") {
  struct Case {
    std::vector<std::string> args;
    std::string file;  // the one the message must name
  };
  const std::string m = "/nonexistent/rise_cli_test/file";
  const Case c = GENERATE_REF(values<Case>({
      {{"rise-hild", "--panel", m + ".yaml", "--source", "mem://x"}, m + ".yaml"},
      {{"rise-hild", "dbc", "decode", m + ".dbc", m + ".log"}, m + ".dbc"},
      {{"rise-hild", "hid", "describe", m + ".rpt"}, m + ".rpt"},
      {{"rise-hild", "verify", "--capture", m + ".log", "--golden", m + ".lcmlog"}, m + ".log"},
      {{"rise-sim", "--robot", m + ".yaml"}, m + ".yaml"},
      {{"rise-sim", "--world", m + ".yaml"}, m + ".yaml"},
      {{"rise-semantic", "register", m + ".pcd", m + "2.pcd"}, m + ".pcd"},
      {{"rise-semantic", "segment", m + ".pcd"}, m + ".pcd"},
      {{"rise-trainer", "check", m + ".yaml"}, m + ".yaml"},
      {{"rise-panel", "emulate", "--panel", m + ".yaml"}, m + ".yaml"},
      {{"rise-panel", "replay", m + ".log", "--to", "mem://x"}, m + ".log"},
      {{"rise-instructor", "scenario", m + ".yaml", "--trainee", "t1"}, m + ".yaml"},
      {{"rise-instructor", "serve", "--token-file", m + ".token"}, m + ".token"},
      {{"rise-instructor", "serve", "--token", "t", "--listen", "127.0.0.1:1", "--designs", m}, m},
  }));
  std::string line;
  for (const auto& a : c.args) line += a + " ";
  INFO(line);
  const Run r = run(c.args);
  CHECK(r.status == 2);
  // The path as given, what failed, and strerror: no made-up line 0.
  CHECK_THAT(r.output, Catch::Contains(c.file + ": cannot open: " + std::strerror(ENOENT)));
  CHECK_THAT(r.output, !Catch::Contains(":0:"));
}

TEST_CASE("a file that is there but wrong is bad input too: exit 2 with file:line", "[cli]") {
  const fs::path bad = fs::temp_directory_path() / ("rise_cli_test_" + std::to_string(::getpid()) + ".ply");
  std::ofstream(bad) << "ply\nformat ascii 1.0\nelement vertex 5\n";
  const Run r = run({"rise-semantic", "register", bad.string(), bad.string()});
  CHECK(r.status == 2);
  CHECK_THAT(r.output, Catch::Contains(bad.string() + ":3: "));
  fs::remove(bad);
}
