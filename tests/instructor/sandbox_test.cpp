// The builders' test drive (instructor/sandbox.hpp) with the real programs
// over real LCM: rise-sim for a shipped task's world and robot on a station
// of its own and rise-trainer run-task scoring it; stopping ends the task
// (the trainer writes its report: interrupted); a new start stops the
// earlier run; a run without a task starts only rise-sim.

#include <catch2/catch.hpp>
#include <json/json.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "instructor/sandbox.hpp"
#include "msgs/channels.hpp"

namespace fs = std::filesystem;
using rise::instructor::Sandbox;
using rise::instructor::SandboxStatus;

namespace {

const std::string kBin = std::string(RISE_BINARY_DIR) + "/bin";
const std::string kTask = std::string(RISE_SOURCE_DIR) + "/sim/training/examples/approach_object.yaml";

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

bool alive(int pid) { return pid > 0 && ::kill(pid, 0) == 0; }

// Polls until `ok` holds or `seconds` pass.
template <class F>
bool eventually(F ok, double seconds) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end) {
    if (ok()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return ok();
}

struct Scratch {
  fs::path dir;
  Scratch() {
    char tmpl[] = "/tmp/rise-sandbox-XXXXXX";
    dir = ::mkdtemp(tmpl);
  }
  ~Scratch() { fs::remove_all(dir); }
};

}  // namespace

TEST_CASE("a sandbox runs a task in rise-sim and rise-trainer and stopping it writes the report", "[instructor][sandbox]") {
  Scratch scratch;
  const std::string station = "sandbox" + std::to_string(::getpid());
  Sandbox sandbox(kBin, rise::msgs::kDefaultLcmUrl);
  auto request = rise::instructor::sandbox_request_for_task(kTask, station, (scratch.dir / "run").string());
  CHECK(request.task_name == "approach_object");
  REQUIRE(request.start);
  CHECK((*request.start)[0] == Approx(4.0));
  CHECK((*request.start)[2] == Approx(36.87));
  SandboxStatus s = sandbox.start(request);
  CHECK(s.active);
  CHECK(alive(s.sim_pid));
  CHECK(alive(s.task_pid));
  // The trainer hears the simulator (it logs the task's start) and keeps scoring.
  INFO(slurp(s.task_log));
  REQUIRE(eventually([&] { return slurp(s.task_log).find("task approach_object started") != std::string::npos; }, 20));
  s = sandbox.status();
  CHECK(s.sim_running);
  CHECK(s.task_running);
  CHECK_FALSE(s.task_done);
  sandbox.stop();
  s = sandbox.status();
  CHECK_FALSE(s.active);
  CHECK(s.task_done);
  CHECK_FALSE(alive(s.sim_pid));
  REQUIRE(fs::exists(s.report_json));
  CHECK(fs::exists(s.report_html));
  Json::Value report;
  std::istringstream in(slurp(s.report_json));
  REQUIRE(Json::parseFromStream(Json::CharReaderBuilder(), in, &report, nullptr));
  CHECK(report["task"].asString() == "approach_object");
  INFO(slurp(s.report_json));
  CHECK(report["end_reason"].asString() == "interrupted");
}

TEST_CASE("a sandbox start stops the earlier run and without a task only rise-sim runs", "[instructor][sandbox]") {
  Scratch scratch;
  const std::string station = "sandboxb" + std::to_string(::getpid());
  Sandbox sandbox(kBin, rise::msgs::kDefaultLcmUrl);
  auto first = sandbox.start(rise::instructor::sandbox_request_for_task(kTask, station, (scratch.dir / "a").string()));
  REQUIRE(alive(first.sim_pid));
  rise::instructor::SandboxRequest drive;
  drive.station = station;
  drive.robot_file = std::string(RISE_SOURCE_DIR) + "/sim/robots/skid4.yaml";
  drive.out_dir = (scratch.dir / "b").string();
  auto second = sandbox.start(drive);
  CHECK_FALSE(alive(first.sim_pid));
  CHECK_FALSE(alive(first.task_pid));
  CHECK(alive(second.sim_pid));
  CHECK(second.task_pid == -1);
  CHECK(second.report_json.empty());
  CHECK(sandbox.status().sim_running);
  sandbox.stop();
  CHECK_FALSE(alive(second.sim_pid));
}
