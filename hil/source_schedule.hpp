#pragma once

// When a source's loop tries its closed transport again (ReopenSchedule)
// and when it builds and writes the source's feedback (FeedbackSchedule):
// the timing of bridge.cpp's one loop, the same for every transport but for
// the policy the transport states (source_transport.hpp). Times are
// monotonic microseconds; nothing here allocates or throws.

#include <cstdint>

#include "hil/source_transport.hpp"

namespace rise::hil {

class ReopenSchedule {
 public:
  /// Back-off: after a failed attempt the next comes min_ms later, doubling
  /// up to max_ms; once open, back to min_ms, and a transport lost again is
  /// tried at once.
  static ReopenSchedule back_off(int64_t min_ms, int64_t max_ms);
  /// Hot-plug by enumeration: cheap (a sysfs walk), so a fixed period from
  /// each attempt rather than a back-off; after an arrival every 20 ms for a
  /// second, as the hidraw node appears only once the kernel's HID driver
  /// has bound the new device's interface.
  static ReopenSchedule enumeration(int64_t period_ms);

  bool due(int64_t now_us) const { return now_us >= next_us_; }
  /// An attempt at now_us (due) opened the transport or not.
  void attempted(int64_t now_us, bool opened);
  /// The device arrived at now_us: try at once, then quickly for a while.
  void arrived(int64_t now_us);

 private:
  ReopenSchedule(bool enumerate, int64_t min_ms, int64_t max_ms);

  bool enumerate_;
  int64_t min_ms_;
  int64_t max_ms_;
  int64_t retry_ms_;
  int64_t next_us_ = 0;
  int64_t fast_until_us_ = 0;
};

class FeedbackSchedule {
 public:
  FeedbackSchedule(FeedbackPolicy policy, int64_t period_ms);

  /// Whether to build the feedback now, for the request of `version`;
  /// `polled`: the loop's input step just made a poll.
  bool due(int64_t now_us, uint64_t version, bool polled) const;
  /// Whether what is built now goes out even when it equals the last written.
  bool resend(int64_t now_us) const;
  /// It was built at now_us for `version`, and written (or unchanged) when
  /// `written`; a failed write is tried again at the next check.
  void built(int64_t now_us, uint64_t version, bool written);
  /// The transport was (re)opened: the next feedback goes out whatever it is.
  void forget() { written_ = false; }

 private:
  FeedbackPolicy policy_;
  int64_t period_us_;
  int64_t next_us_ = 0;
  uint64_t version_ = ~0ull;
  bool written_ = false;
};

}  // namespace rise::hil
