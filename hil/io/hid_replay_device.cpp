#include "hil/io/hid_replay_device.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <thread>
#include <utility>
#include <variant>

namespace rise::hil::io {
namespace {

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
      passes_(address_.start_s, address_.stop_s, address_.loop),
      clock_(address_.speed) {
  pending_.bytes.reserve(max_hid_report_bytes);
  held_.bytes.reserve(max_hid_report_bytes);
  error_.set("%s: not plugged in yet", address_.path.c_str());
}

void HidReplayDevice::emit(int64_t ts) {
  pending_ts_us_ = passes_.play(ts);
  pending_opens_pass_ = new_pass_;
  new_pass_ = false;
  have_pending_ = true;
}

bool HidReplayDevice::fetch() {
  using Kind = HidRecordingRecord::Kind;
  using Place = ReplayPasses::Place;
  if (have_held_) {
    std::swap(pending_, held_);
    have_held_ = false;
    emit(pending_.time_us);
    return true;
  }
  for (;;) {
    if (reader_.next(pending_)) {
      const Place place = passes_.place(pending_.time_us);
      if (place == Place::Before) {
        // Before the window only whether the device is plugged in, and as what, matters.
        if (pending_.kind == Kind::Plug) {
          std::swap(window_plug_, pending_);
          window_plugged_ = true;
        } else if (pending_.kind != Kind::Report) {
          window_plugged_ = false;
        }
        continue;
      }
      if (place == Place::In) {
        if (pending_.kind == Kind::End && passes_.more()) {
          passes_.play(pending_.time_us);  // the recording's end is only the pass's last time
          continue;
        }
        if (window_plugged_ && pending_.kind != Kind::Plug) {
          // Plugged in before the window: plugged in at its start.
          std::swap(held_, pending_);
          have_held_ = true;
          pending_.kind = Kind::Plug;
          pending_.time_us = passes_.window_start_us();
          pending_.line = window_plug_.line;
          pending_.bytes = window_plug_.bytes;
          pending_.identity = window_plug_.identity;
        }
        window_plugged_ = false;
        emit(pending_.time_us);
        return true;
      }
    }
    // The end of a pass: of the file, or of the window.
    window_plugged_ = false;
    if (!passes_.next_pass()) return false;
    loops_done_ = passes_.loops_done();
    reader_.rewind();
    new_pass_ = true;
  }
}

bool HidReplayDevice::next_pending() { return have_pending_ || fetch(); }

bool HidReplayDevice::wait_due(int timeout_ms) {
  if (address_.fast) return true;
  if (!clock_.wait(pending_ts_us_, timeout_ms)) return false;
  if (pending_.kind == HidRecordingRecord::Kind::Report) clock_.count_lateness();
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

}  // namespace rise::hil::io
