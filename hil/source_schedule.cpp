#include "hil/source_schedule.hpp"

#include <algorithm>

namespace rise::hil {

ReopenSchedule::ReopenSchedule(bool enumerate, int64_t min_ms, int64_t max_ms)
    : enumerate_(enumerate), min_ms_(min_ms), max_ms_(max_ms), retry_ms_(min_ms) {}

ReopenSchedule ReopenSchedule::back_off(int64_t min_ms, int64_t max_ms) { return {false, min_ms, max_ms}; }

ReopenSchedule ReopenSchedule::enumeration(int64_t period_ms) { return {true, period_ms, period_ms}; }

void ReopenSchedule::attempted(int64_t now_us, bool opened) {
  if (enumerate_) {
    next_us_ = now_us + (now_us < fast_until_us_ ? 20'000 : min_ms_ * 1000);
    return;
  }
  if (opened) {
    retry_ms_ = min_ms_;
    return;
  }
  next_us_ = now_us + retry_ms_ * 1000;
  retry_ms_ = std::min(retry_ms_ * 2, max_ms_);
}

void ReopenSchedule::arrived(int64_t now_us) {
  next_us_ = 0;
  fast_until_us_ = now_us + 1'000'000;
}

FeedbackSchedule::FeedbackSchedule(FeedbackPolicy policy, int64_t period_ms)
    : policy_(policy), period_us_(period_ms * 1000) {}

bool FeedbackSchedule::due(int64_t now_us, uint64_t version, bool polled) const {
  if (policy_.after_each_poll) return polled;
  return !written_ || now_us >= next_us_ || version != version_;
}

bool FeedbackSchedule::resend(int64_t now_us) const { return !written_ || (policy_.repeat && now_us >= next_us_); }

void FeedbackSchedule::built(int64_t now_us, uint64_t version, bool written) {
  written_ = written;
  version_ = version;
  if (now_us >= next_us_) next_us_ = now_us + period_us_;
}

}  // namespace rise::hil
