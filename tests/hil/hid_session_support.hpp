#pragma once

// What the HID recording tests share (tests/hil, and the uhid tests under
// qemu): a session without a device (the HID emulator plays a timeline in
// its own time and each report it sends becomes an E: line of a
// hid-recorder file, which replay:// then plays as the device; also the
// HID golden's input, make_goldens.sh), a bridge recorded as
// `rise-hild --record` records it, and a recording with one report byte
// changed.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "firmware_protocol/hid_descriptor.hpp"
#include "hil/bridge.hpp"
#include "hil/hid_source.hpp"
#include "hil/io/hid_recording.hpp"
#include "hil/panel_state_message.hpp"
#include "hil/session_recorder.hpp"
#include "msgs/channels.hpp"
#include "msgs/clock.hpp"
#include "panels/hid_emulator.hpp"
#include "panels/panel_definition.hpp"
#include "panels/timeline.hpp"
#include "tests/hil/bridge_test_support.hpp"

namespace rise::hil::test {

struct EmulatedSession {
  int64_t start_us = 1'700'000'000'000'000;  ///< wall-clock time of the timeline's 0
  double unplug_s = -1.0;                    ///< an unplug from here (< 0: none) ...
  double plug_s = -1.0;                      ///< ... to here
  double end_after_s = 0.1;                  ///< the recording ends this long after @end
};

/// Plays `script` on a HidEmulator of `definition`'s source 0 as the device
/// `descriptor` / `identity` describe, in 1 ms steps of its own time, and
/// writes the recording to `path`: plugged in at 0, every report it sends
/// at its step's time, the unplug window, the end. Returns the reports
/// written. Throws what the emulator and the timeline throw.
inline int64_t write_emulated_session(const std::string& path, const panels::PanelDefinition& definition,
                                      const std::string& script, std::span<const uint8_t> descriptor,
                                      const io::HidIdentity& identity, const EmulatedSession& session = {}) {
  const firmware_protocol::HidParseResult parsed = firmware_protocol::parse_hid_descriptor(descriptor);
  if (!parsed) throw std::runtime_error("write_emulated_session: the descriptor does not parse");
  panels::HidEmulator emulator(definition, 0, parsed.descriptor);
  const panels::Timeline timeline = panels::parse_timeline(script, "session.txt", definition);
  io::HidRecordingWriter writer(path, definition.sources[0].name);
  writer.plug(session.start_us, descriptor, identity);
  bool plugged = true;
  std::size_t next = 0;
  for (int64_t ms = 0; ms < 600'000; ++ms) {
    const int64_t now = session.start_us + ms * 1000;
    const double t = static_cast<double>(ms) / 1000.0;
    while (next < timeline.events.size() && timeline.events[next].time_s <= t + 1e-9)
      emulator.apply(timeline.events[next++]);
    if (plugged && session.unplug_s >= 0.0 && t >= session.unplug_s && t < session.plug_s) {
      writer.unplug(now, "unplugged (emulated)");
      plugged = false;
    } else if (!plugged && t >= session.plug_s) {
      writer.plug(now, descriptor, identity);
      plugged = true;
    }
    emulator.tick(now, [&](std::span<const uint8_t> report) {
      if (plugged) writer.report(now, report);
      return true;
    });
    if (emulator.ended()) {
      writer.end(now + static_cast<int64_t>(session.end_after_s * 1e6));
      break;
    }
  }
  return writer.reports();
}

/// A bridge over one HID device (source 0 of `definition`) whose session a
/// SessionRecorder records into `dir`, as `rise-hild --record DIR` does:
/// DIR/<source>.hid and DIR/panel_state.lcmlog. Every published snapshot is
/// in `published` too, each message stamped as rise-hild stamps it (the
/// wall clock when it is published). Started by the constructor.
class RecordedHidSession {
 public:
  RecordedHidSession(const panels::PanelDefinition& definition, std::unique_ptr<io::InputDevice> device,
                     const std::string& dir)
      : definition_(definition), recorder_(dir), channel_(msgs::panel_state_channel("rec")) {
    auto source = std::make_unique<HidSource>(std::move(device), definition_, 0);
    if (!recorder_.record_source(definition_.sources[0].name, *source, 0))
      throw std::runtime_error("RecordedHidSession: the HID device is not recorded");
    recording_ = static_cast<const io::RecordingInputDevice*>(&source->device());
    std::vector<std::unique_ptr<SourceTransport>> transports;
    transports.push_back(std::move(source));
    bridge_ = std::make_unique<Bridge>(definition_, std::move(transports), [this](const PanelSnapshot& snap) {
      const int64_t utime = rise::msgs::wall_us();
      recorder_.record_message(channel_, to_message(definition_, snap, "rec", messages_++, utime, {}));
      published.add(snap);
    });
    bridge_->start();
  }
  ~RecordedHidSession() { stop(); }
  RecordedHidSession(const RecordedHidSession&) = delete;
  RecordedHidSession& operator=(const RecordedHidSession&) = delete;

  /// Stops the bridge: nothing is recorded after it, but the end.
  void stop() { bridge_->stop(); }
  Bridge& bridge() { return *bridge_; }
  const SessionRecorder& recorder() const { return recorder_; }
  const io::RecordingInputDevice& recording() const { return *recording_; }
  int64_t messages() const { return messages_; }

  Published published;

 private:
  panels::PanelDefinition definition_;
  SessionRecorder recorder_;
  std::string channel_;
  std::atomic<int64_t> messages_{0};
  const io::RecordingInputDevice* recording_ = nullptr;
  std::unique_ptr<Bridge> bridge_;
};

/// In the text of a hid-recorder file, sets byte `index` of the first
/// report that changed it (from the report before, of the same length)
/// back to its earlier value. Returns the 1-based line changed, 0 if none.
inline int undo_first_change(std::string& text, std::size_t index) {
  std::string earlier;
  std::size_t length = 0;
  int line_no = 0;
  for (std::size_t pos = 0; pos < text.size();) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    ++line_no;
    if (text.compare(pos, 3, "E: ") == 0) {
      std::istringstream in(text.substr(pos, end - pos));
      std::vector<std::string> words;  // E:, time, length, bytes...
      for (std::string w; in >> w;) words.push_back(w);
      if (length == 0) length = words.size();
      if (words.size() == length && words.size() > 3 + index) {
        if (!earlier.empty() && words[3 + index] != earlier) {
          words[3 + index] = earlier;
          std::string line = words[0];
          for (std::size_t w = 1; w < words.size(); ++w) line += " " + words[w];
          text.replace(pos, end - pos, line);
          return line_no;
        }
        earlier = words[3 + index];
      }
    }
    pos = end + 1;
  }
  return 0;
}

}  // namespace rise::hil::test
