#pragma once

// Child processes for the front door and the multi-process tests: output to
// a log file, stopped by PID, and ended by the kernel if their parent dies.

#include <sys/types.h>

#include <string>
#include <vector>

namespace rise::process {

class ChildProcess {
 public:
  ChildProcess() = default;
  /// Starts argv[0] (a path) with its output appended to log_file ("" →
  /// inherit). Throws std::runtime_error when it cannot be started.
  ChildProcess(const std::vector<std::string>& argv, const std::string& log_file);
  ~ChildProcess();
  ChildProcess(ChildProcess&& other) noexcept;
  ChildProcess& operator=(ChildProcess&& other) noexcept;
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t pid() const { return pid_; }
  const std::string& name() const { return name_; }
  /// True while the child has not exited (reaps it if it has).
  bool running();
  /// Sends a signal (no-op once it exited).
  void signal(int sig);
  /// Waits up to timeout_ms for the exit; returns the exit code, 128+signal
  /// for a killed child, or -1 if it is still running.
  int wait_for(int timeout_ms);
  /// SIGTERM, then SIGKILL after grace_ms; returns the exit code.
  int stop(int grace_ms = 2000);

 private:
  pid_t pid_ = -1;
  int status_ = -1;
  std::string name_;
};

/// Directory of the running executable (from /proc/self/exe).
std::string executable_dir();

}  // namespace rise::process
