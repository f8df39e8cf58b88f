#pragma once

// When the records of a replayed capture are due, shared by the CAN replay
// (ReplayBus) and the HID replay (HidReplayDevice):
// - ReplayClock: record i is due at t0 + (ts_i - ts_first) / speed, t0 the
//   steady-clock time of the first wait: no drift accumulates, and a late
//   record does not delay the next.
// - ReplayPasses: the start/stop window (seconds from a pass's first
//   record) and the loops: each pass after the last by the pass's mean
//   record gap (100 ms for a pass of one record).
// Neither allocates or throws: cyclic-path safe. Not thread-safe (but for
// ReplayClock's lateness figures).

#include <atomic>
#include <chrono>
#include <cstdint>

namespace rise::hil::io {

class ReplayClock {
 public:
  explicit ReplayClock(double speed) : speed_(speed) {}

  /// Waits until the record stamped `ts_us` (the replay's clock, µs) is due,
  /// up to timeout_ms: true once it is (lateness_us() says how late), false
  /// after sleeping timeout_ms (not at all for 0). The first wait anchors
  /// the clock at `ts_us`, now, and sets the thread's timer slack to 1 ns
  /// (PR_SET_TIMERSLACK: the default 50 µs would be most of the lateness).
  bool wait(int64_t ts_us, int timeout_ms);
  /// Anchors without waiting (fast and step replays: times without timing).
  void anchor(int64_t ts_us);
  /// The next wait anchors afresh.
  void reset() { anchored_ = false; }
  bool anchored() const { return anchored_; }
  /// The record time the clock is anchored at.
  int64_t first_us() const { return first_us_; }
  /// Counts the record of the last wait that returned true into the
  /// lateness figures below (a replay counts the records it hands out).
  void count_lateness();
  /// Largest and last (hand-out time - due time) counted, µs; readable from
  /// any thread.
  int64_t max_lateness_us() const { return max_lateness_us_.load(std::memory_order_relaxed); }
  int64_t last_lateness_us() const { return last_lateness_us_.load(std::memory_order_relaxed); }

 private:
  using Clock = std::chrono::steady_clock;
  double speed_;
  bool anchored_ = false;
  Clock::time_point t0_;
  int64_t first_us_ = 0;
  int64_t lateness_us_ = 0;  // of the last wait that returned true
  std::atomic<int64_t> max_lateness_us_{0};
  std::atomic<int64_t> last_lateness_us_{0};
};

class ReplayPasses {
 public:
  /// The window in seconds from a pass's first record (stop_s < 0: to the
  /// end); loop: passes after the first (-1: forever).
  ReplayPasses(double start_s, double stop_s, int loop);

  enum class Place { Before, In, After };
  /// Where the record of the current pass stamped `ts_us` (the file's
  /// clock) falls against the window; the pass's first record starts it.
  Place place(int64_t ts_us);
  /// The file-clock time the window of the current pass starts at.
  int64_t window_start_us() const { return pass_.first_record_us + start_us_; }
  /// A record of the pass at `ts_us` is played; returns its time on the
  /// replay's clock (ts_us plus the offset of the earlier passes).
  int64_t play(int64_t ts_us);
  /// Whether a pass follows this one (loops left).
  bool more() const { return loop_ < 0 || loops_done_ < loop_; }
  /// The pass is over: true when another follows (the caller rewinds its
  /// reader), false at the end or when the pass played nothing (it would
  /// loop forever without a record).
  bool next_pass();
  /// Back to the first pass.
  void restart();
  int loops_done() const { return loops_done_; }

 private:
  // The window in µs from a pass's first record (stop -1: none), the loops asked for.
  int64_t start_us_;
  int64_t stop_us_;
  int loop_;
  // The current pass: its first record, its first and last played, how many it played.
  struct Pass {
    bool started = false;
    int64_t first_record_us = 0, first_played_us = 0, last_played_us = 0;
    uint64_t played = 0;
  };
  Pass pass_;
  int64_t offset_us_ = 0;  // of this pass's times: the earlier passes' spans and gaps
  int loops_done_ = 0;
};

}  // namespace rise::hil::io
