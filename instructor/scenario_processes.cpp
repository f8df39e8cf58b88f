#include "instructor/scenario_processes.hpp"

#include <utility>

namespace rise::instructor {

ScenarioProcesses::ScenarioProcesses(ScenarioCommand command) : command_(std::move(command)) {}

ScenarioProcesses::~ScenarioProcesses() { stop_all(); }

ScenarioRun ScenarioProcesses::start(ScenarioRun run) {
  std::lock_guard lock(mutex_);
  if (auto it = runs_.find(run.trainee); it != runs_.end()) stop_locked(it);
  const std::vector<std::string> argv{command_.program,
                                      "scenario",
                                      run.path,
                                      "--trainee",
                                      run.trainee,
                                      "--seed",
                                      std::to_string(run.seed),
                                      "--lcm",
                                      command_.lcm_url,
                                      "--instructor-key",
                                      command_.instructor_key_file,
                                      "--issuer",
                                      command_.issuer};
  Child child;
  launcher_.run([&] { child.process = std::make_unique<process::ChildProcess>(argv, ""); });
  run.pid = child.process->pid();
  child.run = run;
  runs_[run.trainee] = std::move(child);
  return run;
}

void ScenarioProcesses::stop(const std::string& trainee) {
  std::lock_guard lock(mutex_);
  if (auto it = runs_.find(trainee); it != runs_.end()) stop_locked(it);
}

std::vector<ScenarioRun> ScenarioProcesses::running() {
  std::lock_guard lock(mutex_);
  std::vector<ScenarioRun> out;
  for (auto& [trainee, child] : runs_)
    if (child.process->running()) out.push_back(child.run);
  return out;
}

void ScenarioProcesses::stop_all() {
  {
    std::lock_guard lock(mutex_);
    while (!runs_.empty()) stop_locked(runs_.begin());
  }
  launcher_.stop();
}

void ScenarioProcesses::stop_locked(std::map<std::string, Child>::iterator it) {
  // SIGTERM (SIGKILL after 5 s), on which the run clears its auto_clear faults.
  if (it->second.process->running()) it->second.process->stop(5000);
  runs_.erase(it);
}

}  // namespace rise::instructor
