#pragma once

// replay://FILE.hid[?speed=X][&loop=N][&start=S][&stop=S][&fast=0|1]: a
// HID device played from a hid-recorder file (hid_recording.hpp: our
// recordings and hid-tools' own), as the bridge's HID loop would meet the
// device. Each R: block is a plug: reopen() succeeds once it is due, with
// that block's descriptor and N:/P:/I: identity; each E: report is read()
// when it is due; an unplug, a further R: block (a device plugged in
// again), the end of the recording and the end of the file are a read()
// that returns Disconnected, as an unplugged device's does. After the end
// reopen() stays Disconnected: the panel fails safe as it does for a device
// that never comes back (loop=N plays it again first). A file with no E:
// line plays no report: it plugs in, then ends.
//
// Timing as ReplayBus's (replay_schedule.hpp): record i is due at
// t0 + (ts_i - ts_first) / speed, t0 the steady-clock time of the first
// call that asked for the first record; no drift accumulates and a late
// report does not delay the next; max_lateness_us() says how late reports
// came. fast=1: every record as soon as it is asked for. start/stop: the
// window in seconds from the first record of the file; a device plugged in
// before the window is plugged in at its start. loop=N: N more passes (-1
// forever), each after the last by the pass's mean record gap; a pass that
// begins with the descriptor the device already has goes on without an
// unplug. Output reports are accepted and dropped (counted).
//
// Used from one thread (the source's); the counters from any.

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "hil/io/can_url.hpp"
#include "hil/io/hid_recording.hpp"
#include "hil/io/input_device.hpp"
#include "hil/io/posix_io.hpp"
#include "hil/io/replay_schedule.hpp"

namespace rise::hil::io {

class HidReplayDevice final : public InputDevice {
 public:
  /// Parses the URL and checks the whole file. Throws std::invalid_argument
  /// for a bad URL (ids=, channel= and step= are for CAN logs),
  /// std::runtime_error "FILE:LINE: what" for a file that is missing or
  /// not hid-recorder's. Not for the cyclic path.
  explicit HidReplayDevice(const std::string& url);
  HidReplayDevice(std::string url, ReplayAddress address);
  HidReplayDevice(const HidReplayDevice&) = delete;
  HidReplayDevice& operator=(const HidReplayDevice&) = delete;

  /// Ok once the next plug is due, or while the recording has the device
  /// plugged in (open, or closed by close()); Disconnected before the plug
  /// and after the end. Allocates at a plug (the descriptor); no throw.
  IoStatus reopen() override;
  void close() override { open_ = false; }
  bool is_open() const override { return open_; }
  /// The next report once it is due (waits up to timeout_ms; Timeout when it
  /// is not due by then); Disconnected at an unplug, a new plug and the end.
  /// No allocation, no throw: cyclic-path safe.
  IoStatus read(std::span<uint8_t> report, std::size_t& length, int timeout_ms) override;
  /// Drops the report (counted in writes_dropped()); Ok while open.
  IoStatus write(std::span<const uint8_t> report) override;
  /// Waits up to timeout_ms for the next plug to come due; true when it has
  /// (or the device is plugged in after a close()). No allocation, no throw.
  bool wait_for_arrival(int timeout_ms) override;
  /// The recording says when the device arrives: always true.
  bool hotplug_active() const override { return true; }
  const std::string& hotplug_error() const override { return no_error_; }

  const std::vector<uint8_t>& report_descriptor() const override { return descriptor_; }
  const HidIdentity& identity() const override { return identity_; }
  const std::string& url() const override { return url_; }
  std::string last_error() const override { return error_.get(); }

  /// Largest (read time - due time) of a report so far, µs (0 with fast=1).
  int64_t max_lateness_us() const { return clock_.max_lateness_us(); }
  /// (read time - due time) of the last report read.
  int64_t last_lateness_us() const { return clock_.last_lateness_us(); }
  uint64_t reports_played() const { return reports_played_; }
  /// Plugs handed out by reopen().
  int plugs_played() const { return plugs_played_; }
  /// Restarts of the file for loop= so far.
  int loops_done() const { return loops_done_; }
  uint64_t writes_dropped() const { return writes_dropped_; }
  /// The recording has been played to its end.
  bool ended() const { return ended_; }
  const HidRecordingReader& reader() const { return reader_; }

 private:
  bool fetch();             // pending_ ← the next record to play; false at the end of the last pass
  bool next_pending();      // have_pending_ || fetch()
  void emit(int64_t ts);    // pending_ (at ts, the file's clock) is the next to play
  bool wait_due(int timeout_ms);  // true once pending_ is due; false after timeout_ms
  void unplug(const char* why);
  void finish();

  std::string url_;
  ReplayAddress address_;
  HidRecordingReader reader_;
  ReplayPasses passes_;  // the window and the loops
  ReplayClock clock_;    // anchored when the first record is asked for

  HidRecordingRecord pending_;
  bool have_pending_ = false;
  bool pending_opens_pass_ = false;  // pending_ is the first record of a loop's pass
  bool new_pass_ = false;
  int64_t pending_ts_us_ = 0;        // its time plus the offset of earlier loops
  HidRecordingRecord held_;          // the window's first record, behind the plug made up for it
  bool have_held_ = false;
  HidRecordingRecord window_plug_;   // the last plug before the window
  bool window_plugged_ = false;

  bool plugged_ = false;  // the recording has the device plugged in
  std::vector<uint8_t> descriptor_;
  HidIdentity identity_;
  detail::ErrorText error_;
  const std::string no_error_;

  std::atomic<bool> open_{false};
  std::atomic<bool> ended_{false};
  std::atomic<uint64_t> reports_played_{0};
  std::atomic<int> plugs_played_{0};
  std::atomic<int> loops_done_{0};
  std::atomic<uint64_t> writes_dropped_{0};
};

}  // namespace rise::hil::io
