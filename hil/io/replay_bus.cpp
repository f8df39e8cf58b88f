#include "hil/io/replay_bus.hpp"

#include <algorithm>
#include <utility>

#include "msgs/clock.hpp"

namespace rise::hil::io {

ReplayBus::ReplayBus(std::string url, ReplayAddress address)
    : url_(std::move(url)),
      address_(std::move(address)),
      reader_(address_.path),
      passes_(address_.start_s, address_.stop_s, address_.loop),
      clock_(address_.speed) {}

IoStatus ReplayBus::send(const CanFrame&) {
  ++sends_dropped_;
  return IoStatus::Ok;
}

std::string ReplayBus::last_error() const {
  std::lock_guard lock(mutex_);
  return last_error_;
}

size_t ReplayBus::malformed_lines() const {
  std::lock_guard lock(mutex_);
  return reader_.malformed_count();
}

void ReplayBus::restart() {
  reader_.rewind();
  have_pending_ = false;
  passes_.restart();
  clock_.reset();
  loops_done_ = 0;
}

void ReplayBus::step(int frames) {
  {
    std::lock_guard lock(mutex_);
    steps_ += frames;
  }
  step_cv_.notify_all();
}

bool ReplayBus::awaiting_step() const {
  std::lock_guard lock(mutex_);
  return step_waiters_ > 0;
}

ReplayBus::Progress ReplayBus::progress() const {
  std::lock_guard lock(mutex_);
  Progress p;
  const uint64_t size = reader_.size_bytes();
  p.fraction = size ? static_cast<double>(reader_.bytes_consumed()) / static_cast<double>(size) : 0.0;
  p.log_time_s = clock_.anchored() || address_.fast || address_.step
                     ? static_cast<double>(last_played_ts_us_ - clock_.first_us()) / 1e6
                     : 0.0;
  p.loops_done = loops_done_;
  return p;
}

IoStatus ReplayBus::reopen() {
  std::lock_guard lock(mutex_);
  restart();
  last_error_.clear();
  open_ = true;
  return IoStatus::Ok;
}

bool ReplayBus::fetch_next() {
  for (;;) {
    if (reader_.next(pending_)) {
      const int64_t ts = pending_.frame.timestamp_us;
      const ReplayPasses::Place place = passes_.place(ts);
      if (place == ReplayPasses::Place::Before) continue;
      if (place == ReplayPasses::Place::In) {
        if (!address_.channel.empty() && pending_.channel != address_.channel) continue;
        if (!address_.ids.empty() &&
            std::find(address_.ids.begin(), address_.ids.end(), pending_.frame.id) == address_.ids.end()) {
          continue;
        }
        pending_ts_us_ = passes_.play(ts);
        have_pending_ = true;
        return true;
      }
    }
    // The end of a pass: of the file, or of the window.
    if (!passes_.next_pass()) return false;
    loops_done_ = passes_.loops_done();
    reader_.rewind();
  }
}

IoStatus ReplayBus::receive(CanFrame& frame, int timeout_ms) {
  std::unique_lock lock(mutex_);
  if (!open_) return IoStatus::Disconnected;
  if (!have_pending_ && !fetch_next()) {
    open_ = false;
    last_error_ = address_.path + ": end of the log";
    return IoStatus::Disconnected;
  }
  if (address_.fast || address_.step) {
    if (!clock_.anchored()) clock_.anchor(pending_ts_us_);
    if (address_.step) {
      ++step_waiters_;
      const bool stepped =
          step_cv_.wait_for(lock, std::chrono::milliseconds(std::max(timeout_ms, 0)), [&] { return steps_ > 0; });
      --step_waiters_;
      if (!stepped) return IoStatus::Timeout;
      --steps_;
    }
    last_played_ts_us_ = pending_ts_us_;
    frame = pending_.frame;
    frame.timestamp_us = pending_ts_us_;
    have_pending_ = false;
    // Only receive() writes it (under mutex_): a plain store, no locked add.
    frames_played_.store(frames_played_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    return IoStatus::Ok;
  }
  if (!clock_.wait(pending_ts_us_, timeout_ms)) return IoStatus::Timeout;
  clock_.count_lateness();
  last_played_ts_us_ = pending_ts_us_;
  frame = pending_.frame;
  frame.timestamp_us = msgs::wall_us();
  have_pending_ = false;
  ++frames_played_;
  return IoStatus::Ok;
}

}  // namespace rise::hil::io
