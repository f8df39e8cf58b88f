#pragma once

// The scenario runs the web console starts: one child per trainee,
// `rise-instructor scenario FILE --trainee ID --seed N` (instructor/app/),
// started on one long-lived launcher thread and stopped with SIGTERM, on
// which it clears its auto_clear faults. Thread-safe.

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "instructor/launcher_thread.hpp"
#include "process/child_process.hpp"

namespace rise::instructor {

/// How a run is started: the program and the options every run shares.
struct ScenarioCommand {
  std::string program;  ///< rise-instructor
  std::string lcm_url;
  std::string instructor_key_file;
  std::string issuer;  ///< FaultCommand.issuer
};

/// One trainee's scenario run.
struct ScenarioRun {
  std::string trainee;
  std::string file;  ///< its name in the scenarios folder
  std::string path;  ///< the file to run
  std::string name;  ///< the file's `scenario:`
  uint64_t seed = 0;
  int pid = -1;      ///< the child's, once started
};

class ScenarioProcesses {
 public:
  explicit ScenarioProcesses(ScenarioCommand command);
  ~ScenarioProcesses();
  ScenarioProcesses(const ScenarioProcesses&) = delete;
  ScenarioProcesses& operator=(const ScenarioProcesses&) = delete;

  /// Starts `run` (its trainee's earlier run is stopped first). Returns it
  /// with its pid. Throws std::runtime_error when the child cannot start.
  ScenarioRun start(ScenarioRun run);
  /// Stops and forgets `trainee`'s run, if any.
  void stop(const std::string& trainee);
  /// The runs whose child still runs.
  std::vector<ScenarioRun> running();
  /// Stops every run and the launcher: nothing starts afterwards.
  void stop_all();

 private:
  struct Child {
    ScenarioRun run;
    std::unique_ptr<process::ChildProcess> process;
  };
  /// Stops `it`'s child and forgets it; the caller holds mutex_.
  void stop_locked(std::map<std::string, Child>::iterator it);

  ScenarioCommand command_;
  std::mutex mutex_;
  std::map<std::string, Child> runs_;
  LauncherThread launcher_;
};

}  // namespace rise::instructor
