#include "hil/io/replay_bus.hpp"

#include <sys/prctl.h>

#include <algorithm>
#include <cmath>
#include <thread>
#include <utility>

namespace rise::io {

namespace {

// Time between the last frame of a pass and the first of the next when the
// pass has a single frame (otherwise the pass's mean frame gap is used).
constexpr int64_t kSingleFrameLoopGapUs = 100'000;

int64_t seconds_to_us(double s) { return static_cast<int64_t>(std::llround(s * 1e6)); }

int64_t wall_clock_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace

ReplayBus::ReplayBus(std::string url, ReplayAddress address)
    : url_(std::move(url)),
      address_(std::move(address)),
      reader_(address_.path),
      start_us_(seconds_to_us(address_.start_s)),
      stop_us_(address_.stop_s < 0.0 ? -1 : seconds_to_us(address_.stop_s)) {}

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
  pass_started_ = false;
  pass_played_ = 0;
  loop_offset_us_ = 0;
  anchored_ = false;
  loops_done_ = 0;
}

void ReplayBus::step(int frames) {
  {
    std::lock_guard lock(mutex_);
    steps_ += frames;
  }
  step_cv_.notify_all();
}

ReplayBus::Progress ReplayBus::progress() const {
  std::lock_guard lock(mutex_);
  Progress p;
  const uint64_t size = reader_.size_bytes();
  p.fraction = size ? static_cast<double>(reader_.bytes_consumed()) / static_cast<double>(size) : 0.0;
  p.log_time_s = anchored_ || address_.fast || address_.step
                     ? static_cast<double>(last_played_ts_us_ - ts_first_us_) / 1e6
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
  const int64_t start_us = start_us_;
  const int64_t stop_us = stop_us_;
  for (;;) {
    bool end_of_pass = !reader_.next(pending_);
    if (!end_of_pass) {
      const int64_t ts = pending_.frame.timestamp_us;
      if (!pass_started_) {
        pass_started_ = true;
        pass_first_record_us_ = ts;
      }
      const int64_t since_first = ts - pass_first_record_us_;
      if (stop_us >= 0 && since_first > stop_us) {
        end_of_pass = true;
      } else {
        if (since_first < start_us) continue;
        if (!address_.channel.empty() && pending_.channel != address_.channel) continue;
        if (!address_.ids.empty() &&
            std::find(address_.ids.begin(), address_.ids.end(), pending_.frame.id) == address_.ids.end()) {
          continue;
        }
        if (pass_played_ == 0) pass_first_played_us_ = ts;
        pass_last_played_us_ = ts;
        ++pass_played_;
        pending_ts_us_ = ts + loop_offset_us_;
        have_pending_ = true;
        return true;
      }
    }
    // A pass that played nothing would loop forever without a frame.
    const bool more = address_.loop < 0 || loops_done_ < address_.loop;
    if (!more || pass_played_ == 0) return false;
    const int64_t span = pass_last_played_us_ - pass_first_played_us_;
    const int64_t gap = pass_played_ > 1 ? span / static_cast<int64_t>(pass_played_ - 1)
                                         : kSingleFrameLoopGapUs;
    loop_offset_us_ += span + std::max<int64_t>(gap, 1);
    ++loops_done_;
    reader_.rewind();
    pass_started_ = false;
    pass_played_ = 0;
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
    if (!anchored_) {
      anchored_ = true;
      ts_first_us_ = pending_ts_us_;
    }
    if (address_.step) {
      if (!step_cv_.wait_for(lock, std::chrono::milliseconds(std::max(timeout_ms, 0)), [&] { return steps_ > 0; }))
        return IoStatus::Timeout;
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
  if (!anchored_) {
    anchored_ = true;
    // The default 50 us timer slack of a thread would be most of the
    // lateness: a replay wants its sleeps to end on time.
    ::prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
    t0_ = Clock::now();
    ts_first_us_ = pending_ts_us_;
  }
  const auto offset_us = static_cast<int64_t>(
      std::llround(static_cast<double>(pending_ts_us_ - ts_first_us_) / address_.speed));
  const Clock::time_point due = t0_ + std::chrono::microseconds(offset_us);
  const Clock::time_point now = Clock::now();
  if (due > now) {
    const auto wait = std::chrono::milliseconds(std::max(timeout_ms, 0));
    if (due - now > wait) {
      if (timeout_ms > 0) std::this_thread::sleep_for(wait);
      return IoStatus::Timeout;
    }
    std::this_thread::sleep_until(due);
  }
  const int64_t late_us =
      std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - due).count();
  if (late_us > max_lateness_us_) max_lateness_us_ = late_us;
  last_lateness_us_.store(late_us, std::memory_order_relaxed);
  last_played_ts_us_ = pending_ts_us_;
  frame = pending_.frame;
  frame.timestamp_us = wall_clock_us();
  have_pending_ = false;
  ++frames_played_;
  return IoStatus::Ok;
}

}  // namespace rise::io
