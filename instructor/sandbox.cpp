#include "instructor/sandbox.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <utility>
#include <vector>

#include "sim/training/task_description.hpp"

namespace rise::instructor {
namespace fs = std::filesystem;

namespace {

// rise-sim's --robot: FILE, or FILE@x,y,yaw_deg for a start pose.
std::string robot_argument(const SandboxRequest& r) {
  if (!r.start) return r.robot_file;
  char pose[96];
  std::snprintf(pose, sizeof pose, "@%.4f,%.4f,%.4f", (*r.start)[0], (*r.start)[1], (*r.start)[2]);
  return r.robot_file + pose;
}

// SIGTERM, then SIGKILL after grace_ms; the exit code (-1 when none ran).
int stop_child(std::unique_ptr<process::ChildProcess>& child, int grace_ms) {
  if (!child) return -1;
  const int code = child->running() ? child->stop(grace_ms) : child->wait_for(0);
  child.reset();
  return code;
}

}  // namespace

SandboxRequest sandbox_request_for_task(const std::string& task_file, const std::string& station,
                                        const std::string& out_dir) {
  const auto task = sim::training::load_task_description(task_file);
  SandboxRequest r;
  r.station = station;
  r.world_file = task.world_file;
  r.robot_file = task.robot_file;
  if (task.start) r.start = std::array<double, 3>{task.start->xy_m[0], task.start->xy_m[1], task.start->yaw_rad * 180.0 / M_PI};
  r.task_file = task_file;
  r.task_name = task.name;
  r.out_dir = out_dir;
  return r;
}

Sandbox::Sandbox(std::string bin_dir, std::string lcm_url) : bin_dir_(std::move(bin_dir)), lcm_url_(std::move(lcm_url)) {}

Sandbox::~Sandbox() {
  stop();
  launcher_.stop();
}

SandboxStatus Sandbox::start(const SandboxRequest& request) {
  std::lock_guard lock(mutex_);
  stop_locked();
  request_ = request;
  fs::create_directories(request.out_dir);
  const fs::path out(request.out_dir);
  std::vector<std::string> sim{bin_dir_ + "/rise-sim", "--id", request.station, "--lcm", lcm_url_, "--robot",
                               robot_argument(request)};
  if (!request.world_file.empty()) sim.insert(sim.end(), {"--world", request.world_file});
  std::vector<std::string> trainer;
  if (!request.task_file.empty()) {
    // A report of an earlier run must not pass for this one's.
    for (const char* ext : {".json", ".html"}) fs::remove(out / ("task_" + request.task_name + ext));
    trainer = {bin_dir_ + "/rise-trainer", "run-task", request.task_file, "--id", request.station,
               "--lcm", lcm_url_, "--out", request.out_dir};
  }
  try {
    launcher_.run([&] {
      sim_ = std::make_unique<process::ChildProcess>(sim, (out / "sim.log").string());
      if (!trainer.empty()) trainer_ = std::make_unique<process::ChildProcess>(trainer, (out / "trainer.log").string());
    });
  } catch (...) {
    stop_locked();  // no simulator left without its trainer
    throw;
  }
  active_ = true;
  task_exit_code_ = -1;
  return status_locked();
}

void Sandbox::stop() {
  std::lock_guard lock(mutex_);
  stop_locked();
}

SandboxStatus Sandbox::status() {
  std::lock_guard lock(mutex_);
  return status_locked();
}

void Sandbox::stop_locked() {
  // The trainer first: on SIGTERM it ends the task and writes the report,
  // which needs no simulator.
  const int code = stop_child(trainer_, 5000);
  if (code >= 0 && task_exit_code_ < 0) task_exit_code_ = code;
  stop_child(sim_, 3000);
  active_ = false;
}

SandboxStatus Sandbox::status_locked() {
  SandboxStatus s;
  s.active = active_;
  s.station = request_.station;
  const fs::path out(request_.out_dir);
  if (!request_.out_dir.empty()) {
    s.sim_log = (out / "sim.log").string();
    if (!request_.task_file.empty()) {
      s.task_log = (out / "trainer.log").string();
      s.report_json = (out / ("task_" + request_.task_name + ".json")).string();
      s.report_html = (out / ("task_" + request_.task_name + ".html")).string();
    }
  }
  if (trainer_) {
    s.task_pid = trainer_->pid();
    if (trainer_->running()) {
      s.task_running = true;
    } else {
      // The task ended: its simulator has nothing more to do.
      task_exit_code_ = trainer_->wait_for(0);
      trainer_.reset();
      stop_child(sim_, 3000);
    }
  }
  if (sim_) {
    s.sim_pid = sim_->pid();
    s.sim_running = sim_->running();
  }
  s.task_done = !request_.task_file.empty() && !s.task_running && task_exit_code_ >= 0;
  s.task_exit_code = task_exit_code_;
  return s;
}

}  // namespace rise::instructor
