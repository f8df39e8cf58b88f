#pragma once

// A builder page's test drive: rise-sim for a world and a robot on a station
// id of its own (a sandbox, apart from the classroom's trainees), and
// optionally `rise-trainer run-task` scoring a task there. The user drives
// through the virtual panel page of that station (panel.html?id=STATION),
// which the same server publishes on the same LCM. One run at a time: a new
// start stops the earlier one. Children are started on a launcher thread
// (instructor/launcher_thread.hpp) and stopped with SIGTERM: rise-trainer
// then ends the task ("interrupted") and writes its report. Thread-safe.

#include <array>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "instructor/launcher_thread.hpp"
#include "process/child_process.hpp"

namespace rise::instructor {

/// What to run.
struct SandboxRequest {
  std::string station;     ///< the trainee id of the channels (rise/<station>/...), e.g. "sandbox"
  std::string world_file;  ///< rise-sim --world
  std::string robot_file;  ///< rise-sim --robot
  /// The robot's start: x, y (m), yaw (deg); none: the world's robot_start.
  std::optional<std::array<double, 3>> start;
  std::string task_file;   ///< "" → no task: only rise-sim runs
  std::string task_name;   ///< the task file's `task:` (names its report: task_<name>.json)
  std::string out_dir;     ///< the children's logs and the task's report (made if missing)
};

/// A request for `task_file`'s world, robot and start on `station`, its
/// report in `out_dir`. Throws std::runtime_error "file:line: key: ..." for a
/// task the loader refuses.
SandboxRequest sandbox_request_for_task(const std::string& task_file, const std::string& station,
                                        const std::string& out_dir);

struct SandboxStatus {
  bool active = false;        ///< a run was started and not stopped
  std::string station;
  bool sim_running = false;
  bool task_running = false;  ///< rise-trainer still scores
  bool task_done = false;     ///< rise-trainer exited (its report, if written, is at report_json)
  int task_exit_code = -1;    ///< once task_done
  int sim_pid = -1, task_pid = -1;
  std::string report_json;    ///< the paths the report goes to ("" without a task)
  std::string report_html;
  std::string sim_log, task_log;
};

class Sandbox {
 public:
  /// `bin_dir`: where rise-sim and rise-trainer are (the build's bin/, the
  /// installed programs' folder); `lcm_url`: the LCM the server's virtual
  /// panels publish on.
  Sandbox(std::string bin_dir, std::string lcm_url);
  ~Sandbox();
  Sandbox(const Sandbox&) = delete;
  Sandbox& operator=(const Sandbox&) = delete;

  /// Stops the earlier run, then starts rise-sim and (with a task) rise-trainer
  /// run-task. The report files of an earlier run in out_dir are removed first.
  /// Throws std::runtime_error when a child cannot start.
  SandboxStatus start(const SandboxRequest& request);
  /// Stops the run: rise-trainer first (it writes its report), then rise-sim.
  void stop();
  /// Where the run is; once the task ended, its rise-sim is stopped here.
  SandboxStatus status();

 private:
  SandboxStatus status_locked();
  void stop_locked();

  std::string bin_dir_;
  std::string lcm_url_;
  std::mutex mutex_;
  SandboxRequest request_;
  bool active_ = false;
  int task_exit_code_ = -1;
  std::unique_ptr<process::ChildProcess> sim_, trainer_;
  LauncherThread launcher_;
};

}  // namespace rise::instructor
