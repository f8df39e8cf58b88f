#include "hil/io/replay_schedule.hpp"

#include <sys/prctl.h>

#include <algorithm>
#include <cmath>
#include <thread>

namespace rise::hil::io {
namespace {

// Time between the last record of a pass and the first of the next when the
// pass has a single record (otherwise the pass's mean record gap is used).
constexpr int64_t kSingleRecordLoopGapUs = 100'000;

int64_t seconds_to_us(double s) { return static_cast<int64_t>(std::llround(s * 1e6)); }

}  // namespace

void ReplayClock::anchor(int64_t ts_us) {
  anchored_ = true;
  t0_ = Clock::now();
  first_us_ = ts_us;
}

bool ReplayClock::wait(int64_t ts_us, int timeout_ms) {
  if (!anchored_) {
    ::prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
    anchor(ts_us);
  }
  const auto offset_us = static_cast<int64_t>(std::llround(static_cast<double>(ts_us - first_us_) / speed_));
  const Clock::time_point due = t0_ + std::chrono::microseconds(offset_us);
  const Clock::time_point now = Clock::now();
  if (due > now) {
    const auto wait = std::chrono::milliseconds(std::max(timeout_ms, 0));
    if (due - now > wait) {
      if (timeout_ms > 0) std::this_thread::sleep_for(wait);
      return false;
    }
    std::this_thread::sleep_until(due);
  }
  lateness_us_ = std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - due).count();
  return true;
}

void ReplayClock::count_lateness() {
  if (lateness_us_ > max_lateness_us_.load(std::memory_order_relaxed))
    max_lateness_us_.store(lateness_us_, std::memory_order_relaxed);
  last_lateness_us_.store(lateness_us_, std::memory_order_relaxed);
}

ReplayPasses::ReplayPasses(double start_s, double stop_s, int loop)
    : start_us_(seconds_to_us(start_s)), stop_us_(stop_s < 0.0 ? -1 : seconds_to_us(stop_s)), loop_(loop) {}

ReplayPasses::Place ReplayPasses::place(int64_t ts_us) {
  if (!pass_.started) {
    pass_.started = true;
    pass_.first_record_us = ts_us;
  }
  const int64_t since_first = ts_us - pass_.first_record_us;
  if (stop_us_ >= 0 && since_first > stop_us_) return Place::After;
  return since_first < start_us_ ? Place::Before : Place::In;
}

int64_t ReplayPasses::play(int64_t ts_us) {
  if (pass_.played == 0) pass_.first_played_us = ts_us;
  pass_.last_played_us = ts_us;
  ++pass_.played;
  return ts_us + offset_us_;
}

bool ReplayPasses::next_pass() {
  if (!more() || pass_.played == 0) return false;
  const int64_t span = pass_.last_played_us - pass_.first_played_us;
  const int64_t gap = pass_.played > 1 ? span / static_cast<int64_t>(pass_.played - 1) : kSingleRecordLoopGapUs;
  offset_us_ += span + std::max<int64_t>(gap, 1);
  ++loops_done_;
  pass_ = {};
  return true;
}

void ReplayPasses::restart() {
  pass_ = {};
  offset_us_ = 0;
  loops_done_ = 0;
}

}  // namespace rise::hil::io
