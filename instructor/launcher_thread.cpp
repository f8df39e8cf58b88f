#include "instructor/launcher_thread.hpp"

#include <stdexcept>

namespace rise::instructor {

LauncherThread::LauncherThread() : thread_([this] { loop(); }) {}

LauncherThread::~LauncherThread() { stop(); }

void LauncherThread::run(std::function<void()> f) {
  std::packaged_task<void()> task(std::move(f));
  auto done = task.get_future();
  {
    std::lock_guard lock(mutex_);
    if (stopping_) throw std::runtime_error("the server is stopping: no child is started");
    tasks_.push_back(std::move(task));
  }
  wake_.notify_one();
  done.get();
}

void LauncherThread::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void LauncherThread::loop() {
  for (;;) {
    std::packaged_task<void()> task;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return !tasks_.empty() || stopping_; });
      if (tasks_.empty()) return;
      task = std::move(tasks_.front());
      tasks_.pop_front();
    }
    task();
  }
}

}  // namespace rise::instructor
