#pragma once

// A scripted console session: "time control value" lines that the emulator
// plays as if a person moved the sticks (panels/scripts/*.txt).
//
//   # t[s]  control   value
//   0.0     deadman   pressed
//   0.5     drive_y   0.8        # axes -1..1
//   0.5     speed     fast       # switches by label or index
//   4.0     @silent              # firmware stops transmitting (source loss)
//
// Directives: @silent, @resume, @status init|operational|fault|shutdown,
// @corrupt N (the next N frames carry a wrong CRC), @invalid CONTROL (the
// axis or switch reads "not available"), @end (the emulator exits).

#include <string>
#include <vector>

#include "panels/panel_definition.hpp"

namespace rise::panels {

struct TimelineEvent {
  enum class Kind { Set, Silent, Resume, Status, Corrupt, Invalid, End };
  double time_s = 0.0;
  Kind kind = Kind::Set;
  std::size_t control = 0;  ///< Set / Invalid: index into PanelDefinition::controls
  float axis = 0.0f;        ///< Set on an axis
  bool pressed = false;     ///< Set on a button
  uint8_t position = 0;     ///< Set on a switch
  int count = 0;            ///< Corrupt: number of frames
  uint8_t status = 1;       ///< Status: firmware_protocol::PanelStatus value
  int line = 0;
};

struct Timeline {
  std::string file;
  std::vector<TimelineEvent> events;  ///< sorted by time (stable)
  double end_time_s() const { return events.empty() ? 0.0 : events.back().time_s; }
};

/// Loads a timeline against a panel definition. Throws "file:line: ..." for
/// an unknown control, a value out of range, time going backwards.
Timeline load_timeline(const std::string& path, const PanelDefinition& definition);
Timeline parse_timeline(const std::string& text, const std::string& file,
                        const PanelDefinition& definition);

}  // namespace rise::panels
