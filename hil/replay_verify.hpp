#pragma once

// Verified replay: feeds a panel's PanelMapper from capture files in the
// captures' own time (each record's timestamp is its now_us: deterministic,
// as fast as the files read), evaluates the panel at each PanelState of a
// golden LCM log and compares the two field by field.
//
// Captures are what `rise-hild --record DIR` writes: a candump log per CAN
// source (<source>.log), a Modbus transaction trace per Modbus source
// (<source>.modbus.log), a hid-recorder file per HID source (<source>.hid:
// each R: block attaches its descriptor, each E: report is decoded at its
// time). Frames the daemon sent (" T", "Tx") are left out.
// Vector ASC and PEAK TRC logs replay too, but their times count from the
// measurement's start, so only a candump log's epoch times line up with a
// golden's utime; so does a hid-recorder file only with our `# start`
// line (hid-tools' own count from their first report). The records go through the same calls the live bridge
// makes (hil/source_input.hpp). All of this is offline: it allocates, and
// throws on bad input; nothing here is for the cyclic path.
//
// What a capture cannot say is taken as follows. A CAN log has no record of
// the transport opening or closing: a CAN source is connected from its
// capture's first record, and where the golden says a source was
// (dis)connected the replay follows it (connect before the frames since the
// previous message, disconnect after them). A Modbus trace records its
// link's reopens and closes itself, a HID recording its plugs and unplugs.
//
// A frame and a publish can race by microseconds in the live daemon (and
// ages in a failsafe reason round to milliseconds), so a golden message
// matches when the replayed state at its utime, or at utime ± the time
// tolerance with the records inside that window applied one by one, matches.
// The live daemon also evaluates the panel between publishes (for feedback);
// filters whose output depends on when they are sampled (low-pass, toggle,
// edge, long press, debounce) are sampled here at the golden's times only,
// which the axis tolerance absorbs for low-pass filters.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "hil/panel_mapper.hpp"
#include "rise_msgs/PanelState.hpp"

namespace rise::hil {

/// One capture file and the panel source it holds.
struct Capture {
  std::string path;
  std::size_t source = 0;
};

/// The source a capture file belongs to, from the name `rise-hild --record`
/// gives it: SOURCE.log, SOURCE.modbus.log or SOURCE.hid (SOURCE=PATH names
/// it explicitly); a panel with one source takes any file. Throws
/// std::invalid_argument naming the path when no source fits, or the
/// file's kind (CAN log, Modbus trace, hid-recorder) is not the source's
/// protocol.
Capture capture_for(const panels::PanelDefinition& definition, const std::string& path);

/// The captures `rise-hild --record` wrote into `dir`: one per source of
/// the definition. Throws std::invalid_argument naming a missing file.
std::vector<Capture> captures_in(const panels::PanelDefinition& definition, const std::string& dir);

/// The records of every capture, merged by time, applied to a PanelMapper.
class CaptureReplay {
 public:
  /// Opens the captures. Throws std::runtime_error "path:line: what" for
  /// an unreadable line (here or from the calls below: the files are read
  /// as the replay goes; a HID recording is checked whole here).
  CaptureReplay(const panels::PanelDefinition& definition, std::vector<Capture> captures);
  ~CaptureReplay();
  CaptureReplay(const CaptureReplay&) = delete;
  CaptureReplay& operator=(const CaptureReplay&) = delete;

  /// Time of the next record (µs, the capture's clock), nullopt at the end.
  std::optional<int64_t> next_time_us() const;
  /// Applies the next record, if any.
  void apply_next();
  /// Applies every record with a time ≤ t_us.
  void advance_to(int64_t t_us);
  /// Time of the earliest first record of the captures (0 when all are empty).
  int64_t start_us() const { return start_us_; }
  /// Records applied so far.
  int64_t records_applied() const { return applied_; }

  /// Opens or closes a source's transport at now_us, as the bridge would.
  void set_connected(std::size_t source, bool connected, int64_t now_us);
  bool connected(std::size_t source) const;
  /// True for the sources whose capture records their link (Modbus traces, HID recordings).
  bool records_link(std::size_t source) const;

  PanelMapper& mapper() { return mapper_; }
  const panels::PanelDefinition& definition() const { return mapper_.definition(); }

  struct Feed;  ///< one capture being read (replay_verify.cpp)

 private:
  Feed* next_feed() const;

  PanelMapper mapper_;
  std::vector<std::unique_ptr<Feed>> feeds_;
  std::vector<bool> connected_;
  std::vector<bool> started_;  // a record of the source was applied
  int64_t start_us_ = 0;
  int64_t applied_ = 0;
};

struct VerifySettings {
  float axis_tolerance = 1e-3f;      ///< |expected − got| allowed on an axis
  int64_t time_tolerance_us = 2000;  ///< a message may match the state this far from its utime
};

/// One field that differs between a golden PanelState and the replay.
struct VerifyDifference {
  std::size_t message = 0;      ///< index in the golden stream
  int64_t seq = 0;              ///< the golden message's seq
  int64_t utime = 0;            ///< the golden message's utime
  double time_s = 0.0;          ///< utime in seconds since the capture's start
  std::string field;            ///< a control name, or failsafe, failsafe_causes, failsafe_reason, deadman
  std::string expected;
  std::string got;
  std::vector<std::string> also;  ///< the other fields that differ in that message
};

struct VerifyReport {
  std::size_t messages = 0;        ///< golden messages that matched
  std::size_t off_time = 0;        ///< of those, matched only within the time tolerance
  int64_t records = 0;             ///< capture records applied
  int64_t start_us = 0;            ///< the capture's start
  std::optional<VerifyDifference> difference;  ///< the first one; verification stops there
  bool passed() const { return !difference.has_value(); }
};

/// Replays the captures against the golden messages (in their order).
/// Throws std::invalid_argument when the golden is of another panel (panel
/// id or control names), std::runtime_error for unreadable captures.
VerifyReport verify_replay(const panels::PanelDefinition& definition, std::vector<Capture> captures,
                           std::span<const rise_msgs::PanelState> golden, const VerifySettings& settings = {});

/// The first field in which `got` differs from `expected`: failsafe,
/// failsafe_reason (a number of milliseconds in it, "for 53 ms", may be off
/// by the time tolerance), deadman, each axis (within the axis tolerance),
/// button and switch (position and label), then each source's error counters
/// (crc, counter, length, unknown id, timeouts, exceptions, error frames,
/// bus-offs, bus state: a corrupt frame that heals within recovery_frames
/// before the next publish shows only there). seq, utime, ids, frames_ok,
/// reconnects and ages are not compared. nullopt when they match. Fills
/// field ("drive_y", "console.crc_errors"), expected, got and also.
std::optional<VerifyDifference> compare_panel_states(const rise_msgs::PanelState& expected,
                                                     const rise_msgs::PanelState& got,
                                                     const VerifySettings& settings = {});

/// One line for a difference, e.g. "t=2.345 s (message 234, seq 240):
/// drive_y: expected 0.8000, got 0.0000; also differ: failsafe".
std::string describe(const VerifyDifference& difference);

/// The PanelState messages of an LCM log (lcm-logger's event log format).
struct PanelStateLog {
  std::string channel;
  std::vector<rise_msgs::PanelState> messages;
};
/// Reads the messages on `channel`, or, when it is empty, on the one channel
/// whose name ends in "/panel_state". Throws std::runtime_error naming the
/// path when it cannot be read, has no such channel or several, or an event
/// does not decode.
PanelStateLog read_panel_state_log(const std::string& path, const std::string& channel = "");

}  // namespace rise::hil
