#include "hil/io/hid_replay_device.hpp"

#include <sys/prctl.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <thread>
#include <utility>
#include <variant>

namespace rise::io {
namespace {

// Time between the last record of a pass and the first of the next when the
// pass has a single record (otherwise the pass's mean record gap is used).
constexpr int64_t kSingleRecordLoopGapUs = 100'000;

int64_t seconds_to_us(double s) { return static_cast<int64_t>(std::llround(s * 1e6)); }

ReplayAddress hid_replay_address(const std::string& url) {
  const CanAddress parsed = parse_can_url(url);
  const auto* address = std::get_if<ReplayAddress>(&parsed);
  if (!address) throw std::invalid_argument("'" + url + "': a HID replay is replay://FILE.hid");
  if (!address->ids.empty() || !address->channel.empty() || address->step)
    throw std::invalid_argument("'" + url +
                                "': ids=, channel= and step= are for CAN logs (a HID replay takes speed, loop, "
                                "start, stop, fast)");
  return *address;
}

}  // namespace

HidReplayDevice::HidReplayDevice(const std::string& url) : HidReplayDevice(url, hid_replay_address(url)) {}

HidReplayDevice::HidReplayDevice(std::string url, ReplayAddress address)
    : url_(std::move(url)),
      address_(std::move(address)),
      reader_(address_.path),
      start_us_(seconds_to_us(address_.start_s)),
      stop_us_(address_.stop_s < 0.0 ? -1 : seconds_to_us(address_.stop_s)) {
  pending_.bytes.reserve(max_hid_report_bytes);
  held_.bytes.reserve(max_hid_report_bytes);
  error_.set("%s: not plugged in yet", address_.path.c_str());
}

void HidReplayDevice::emit(int64_t ts) {
  if (pass_played_ == 0) pass_first_played_us_ = ts;
  pass_last_played_us_ = std::max(pass_last_played_us_, ts);
  ++pass_played_;
  pending_ts_us_ = ts + loop_offset_us_;
  pending_opens_pass_ = new_pass_;
  new_pass_ = false;
  have_pending_ = true;
}

bool HidReplayDevice::fetch() {
  using Kind = HidRecordingRecord::Kind;
  if (have_held_) {
    std::swap(pending_, held_);
    have_held_ = false;
    emit(pending_.time_us);
    return true;
  }
  for (;;) {
    bool end_of_pass = !reader_.next(pending_);
    const bool more = address_.loop < 0 || loops_done_ < address_.loop;
    if (!end_of_pass) {
      int64_t ts = pending_.time_us;
      if (!pass_started_) {
        pass_started_ = true;
        pass_first_record_us_ = ts;
        pass_last_played_us_ = ts;
        window_plugged_ = false;
      }
      const int64_t since_first = ts - pass_first_record_us_;
      if (stop_us_ >= 0 && since_first > stop_us_) {
        end_of_pass = true;
      } else if (since_first < start_us_) {
        // Before the window: only whether the device is plugged in, and as what, matters.
        if (pending_.kind == Kind::Plug) {
          std::swap(window_plug_, pending_);
          window_plugged_ = true;
        } else if (pending_.kind != Kind::Report) {
          window_plugged_ = false;
        }
        continue;
      } else if (pending_.kind == Kind::End && more) {
        // The recording's end is only the pass's last time when another pass follows.
        pass_last_played_us_ = std::max(pass_last_played_us_, ts);
        continue;
      } else {
        if (window_plugged_ && pending_.kind != Kind::Plug) {
          // The device was plugged in before the window: plugged in at its start.
          std::swap(held_, pending_);
          have_held_ = true;
          pending_.bytes = window_plug_.bytes;
          pending_.identity = window_plug_.identity;
          pending_.kind = Kind::Plug;
          pending_.line = window_plug_.line;
          ts = pass_first_record_us_ + start_us_;
          pending_.time_us = ts;
        }
        window_plugged_ = false;
        emit(ts);
        return true;
      }
    }
    // A pass that played nothing would loop forever without a record.
    if (!more || pass_played_ == 0) return false;
    const int64_t span = pass_last_played_us_ - pass_first_played_us_;
    const int64_t gap =
        pass_played_ > 1 ? span / static_cast<int64_t>(pass_played_ - 1) : kSingleRecordLoopGapUs;
    loop_offset_us_ += span + std::max<int64_t>(gap, 1);
    ++loops_done_;
    reader_.rewind();
    pass_started_ = false;
    pass_played_ = 0;
    new_pass_ = true;
  }
}

bool HidReplayDevice::next_pending() { return have_pending_ || fetch(); }

bool HidReplayDevice::wait_due(int timeout_ms) {
  if (address_.fast) return true;
  if (!anchored_) {
    anchored_ = true;
    // The default 50 µs timer slack of a thread would be most of the
    // lateness: a replay wants its sleeps to end on time.
    ::prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
    t0_ = Clock::now();
    ts_first_us_ = pending_ts_us_;
  }
  const auto offset_us =
      static_cast<int64_t>(std::llround(static_cast<double>(pending_ts_us_ - ts_first_us_) / address_.speed));
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
  if (pending_.kind == HidRecordingRecord::Kind::Report) {
    const int64_t late_us = std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - due).count();
    if (late_us > max_lateness_us_) max_lateness_us_ = late_us;
    last_lateness_us_.store(late_us, std::memory_order_relaxed);
  }
  return true;
}

void HidReplayDevice::unplug(const char* why) {
  open_ = false;
  plugged_ = false;
  error_.set("%s:%d: %s", address_.path.c_str(), pending_.line, why);
}

void HidReplayDevice::finish() {
  open_ = false;
  plugged_ = false;
  ended_ = true;
  have_pending_ = false;
  error_.set("%s: end of the recording", address_.path.c_str());
}

IoStatus HidReplayDevice::reopen() {
  using Kind = HidRecordingRecord::Kind;
  if (open_) return IoStatus::Ok;
  for (;;) {
    if (ended_ || !next_pending()) {
      finish();
      return IoStatus::Disconnected;
    }
    const bool due = wait_due(0);
    if (!due) {
      // Closed by close() while the recording has it plugged in: open again.
      if (plugged_) break;
      error_.set("%s: not plugged in yet", address_.path.c_str());
      return IoStatus::Disconnected;
    }
    have_pending_ = false;
    switch (pending_.kind) {
      case Kind::Plug:
        descriptor_ = pending_.bytes;
        identity_ = pending_.identity;
        plugged_ = true;
        ++plugs_played_;
        open_ = true;
        error_.clear();
        return IoStatus::Ok;
      case Kind::Report: continue;  // came while closed: lost, as a closed device's are
      case Kind::Unplug: plugged_ = false; continue;
      case Kind::End: finish(); return IoStatus::Disconnected;
    }
  }
  open_ = true;
  error_.clear();
  return IoStatus::Ok;
}

IoStatus HidReplayDevice::read(std::span<uint8_t> report, std::size_t& length, int timeout_ms) {
  using Kind = HidRecordingRecord::Kind;
  length = 0;
  if (!open_) return IoStatus::Disconnected;
  for (;;) {
    if (!next_pending()) {
      finish();
      return IoStatus::Disconnected;
    }
    // A loop's pass that begins with the device as it is goes on seamlessly.
    if (pending_.kind == Kind::Plug && pending_opens_pass_ && pending_.bytes == descriptor_ &&
        pending_.identity == identity_) {
      have_pending_ = false;
      continue;
    }
    if (!wait_due(timeout_ms)) return IoStatus::Timeout;
    switch (pending_.kind) {
      case Kind::Report: {
        length = std::min(pending_.bytes.size(), report.size());
        std::memcpy(report.data(), pending_.bytes.data(), length);
        have_pending_ = false;
        reports_played_.store(reports_played_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
        return IoStatus::Ok;
      }
      case Kind::Plug:  // plugged in again: the next reopen() takes it
        unplug("plugged in again (a new R: block)");
        return IoStatus::Disconnected;
      case Kind::Unplug:
        have_pending_ = false;
        unplug("unplugged");
        return IoStatus::Disconnected;
      case Kind::End:
        finish();
        return IoStatus::Disconnected;
    }
  }
}

IoStatus HidReplayDevice::write(std::span<const uint8_t>) {
  if (!open_) return IoStatus::Disconnected;
  writes_dropped_.store(writes_dropped_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  return IoStatus::Ok;
}

bool HidReplayDevice::wait_for_arrival(int timeout_ms) {
  if (!open_ && plugged_) return true;  // closed, not unplugged
  if (open_ || ended_ || !next_pending()) {
    if (timeout_ms > 0) std::this_thread::sleep_for(std::chrono::milliseconds(timeout_ms));
    return false;
  }
  // Whatever comes next while the device is away (its plug, or a report or
  // unplug the recording has before it) is reopen()'s to take once due.
  return wait_due(timeout_ms);
}

}  // namespace rise::io
