#pragma once

// One long-lived thread that runs what request threads hand it and waits for
// it. Children are started there: a child dies with the thread that forked
// it (PR_SET_PDEATHSIG, process/child_process.hpp), and request threads come
// and go.

#include <condition_variable>
#include <deque>
#include <functional>
#include <future>
#include <mutex>
#include <thread>

namespace rise::instructor {

class LauncherThread {
 public:
  /// Starts the thread.
  LauncherThread();
  ~LauncherThread();
  LauncherThread(const LauncherThread&) = delete;
  LauncherThread& operator=(const LauncherThread&) = delete;

  /// Runs `f` on the launcher thread and waits for it; rethrows what it
  /// threw. Throws std::runtime_error once stopped.
  void run(std::function<void()> f);
  /// Runs what is queued, then ends the thread.
  void stop();

 private:
  void loop();

  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::packaged_task<void()>> tasks_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace rise::instructor
