#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>

#include "hil/io/can_bus.hpp"
#include "hil/io/can_log.hpp"
#include "hil/io/can_url.hpp"
#include "hil/io/replay_schedule.hpp"

namespace rise::hil::io {

/// replay://PATH?speed=&loop=&start=&stop=&ids=&channel=&fast=: a bus that
/// plays a CAN log (candump, ASC, TRC) as if a device sent it. Frame i is
/// due at t0 + (ts_i - ts_first) / speed, with t0 the steady-clock time of
/// the first receive(): no drift accumulates, a late frame does not delay
/// the next one. Received frames carry the wall-clock time (or, with
/// fast=1, the recorded time, delivered as fast as asked for). At the end
/// of the log (after the loops) the bus closes: receive() returns
/// Disconnected, like an unplugged device; reopen() plays it again from
/// the start. The first timed receive() sets its thread's timer slack to
/// 1 ns (PR_SET_TIMERSLACK), so sleeps end when the frame is due. send() is accepted and dropped (counted). One thread may
/// send while another receives; reopen() waits for a receive in progress.
class ReplayBus final : public CanBus {
 public:
  /// Opens the log. Throws std::runtime_error naming the path when it is
  /// missing or not a known format.
  ReplayBus(std::string url, ReplayAddress address);
  ReplayBus(const ReplayBus&) = delete;
  ReplayBus& operator=(const ReplayBus&) = delete;

  /// Drops the frame (counted in sends_dropped()); Ok. Safe in the cyclic path.
  IoStatus send(const CanFrame& frame) override;
  /// The next frame of the log that passes the filters, once it is due:
  /// waits up to timeout_ms (0 = poll), Timeout when it is not due by then.
  /// Disconnected at the end of the log. Does not throw; no allocation
  /// besides the reader's line buffer.
  IoStatus receive(CanFrame& frame, int timeout_ms) override;
  /// Restarts from the first record, with a new time anchor and no loop done.
  IoStatus reopen() override;
  bool is_open() const override { return open_; }
  const std::string& url() const override { return url_; }
  std::string last_error() const override;

  /// Largest (receive time - due time) so far, in microseconds (0 with fast=1).
  int64_t max_lateness_us() const { return clock_.max_lateness_us(); }
  /// (receive time - due time) of the frame the last receive() handed out.
  int64_t last_lateness_us() const { return clock_.last_lateness_us(); }
  /// Frames handed out by receive() since construction.
  uint64_t frames_played() const { return frames_played_; }
  /// Restarts of the log for loop= since the last (re)open.
  int loops_done() const { return loops_done_; }
  /// Frames given to send() and dropped.
  uint64_t sends_dropped() const { return sends_dropped_; }
  /// Malformed lines the reader skipped in the current pass.
  size_t malformed_lines() const;

  /// step=1: lets `frames` more frames out (each receive() takes one).
  void step(int frames = 1);
  /// step=1: a receive() is waiting for a step (a stepping front end's "waiting").
  bool awaiting_step() const;
  /// Where the replay is: the current pass's share of the file read (0..1)
  /// and the recorded time of the last frame handed out, from the first.
  struct Progress {
    double fraction = 0.0;
    double log_time_s = 0.0;
    int loops_done = 0;
  };
  Progress progress() const;

 private:
  bool fetch_next();  // fills pending_; false at the end of the last pass
  void restart();

  std::string url_;
  ReplayAddress address_;
  mutable std::mutex mutex_;
  CanLogReader reader_;
  ReplayPasses passes_;  // the window and the loops
  ReplayClock clock_;    // anchored at the first receive
  std::string last_error_;

  CanLogRecord pending_;
  bool have_pending_ = false;
  int64_t pending_ts_us_ = 0;  // recorded time plus the offset of earlier loops

  std::atomic<bool> open_{true};
  std::atomic<uint64_t> frames_played_{0};
  std::atomic<int> loops_done_{0};
  std::atomic<uint64_t> sends_dropped_{0};
  std::condition_variable step_cv_;
  int64_t steps_ = 0;          // step=1: frames allowed out (under mutex_)
  int step_waiters_ = 0;       // step=1: receive() calls waiting for a step (under mutex_)
  int64_t last_played_ts_us_ = 0;
};

}  // namespace rise::hil::io
