#pragma once

// A HID session without a device: the HID emulator (panels/) plays a
// timeline in its own time and each report it sends becomes an E: line of
// a hid-recorder file, which replay:// then plays as the device. Shared by
// the HID replay tests and the HID golden's input (make_goldens.sh).

#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>

#include "firmware_protocol/hid_descriptor.hpp"
#include "hil/io/hid_recording.hpp"
#include "panels/hid_emulator.hpp"
#include "panels/panel_definition.hpp"
#include "panels/timeline.hpp"

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

}  // namespace rise::hil::test
