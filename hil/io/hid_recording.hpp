#pragma once

// A HID device's input in hid-recorder's text format (hid-tools,
// gitlab.freedesktop.org/libevdev/hid-tools: hid-recorder writes it from a
// hidraw node, hid-replay plays it back through uhid). `rise-hild --record
// DIR` writes one per hid source (DIR/<source>.hid); replay:// plays any
// such file as the device (hid_replay_device.hpp) and `rise-hild verify`
// replays it against a golden PanelState log. The lines, as
// hidtools/hidraw.py writes them:
//
//   # TEXT                          a comment
//   R: LEN HEX...                   the report descriptor: LEN (decimal) bytes in hex
//   N: NAME                         the device's name (HIDIOCGRAWNAME)
//   P: PHYS                         its physical path (HIDIOCGRAWPHYS; only when known)
//   I: BUS VID PID                  in hex: bus 3 USB, 5 Bluetooth (linux/input.h BUS_*)
//   E: SEC.USEC LEN HEX...          one input report (with its id byte when the
//                                   descriptor uses ids), at SEC.USEC (six digits of
//                                   microseconds) after the file's first report,
//                                   which is E: 000000.000000
//   D: N                            the lines after it are of device N (hid-recorder
//                                   of several nodes); only device 0 is read here
//
// hid-recorder records one plug of a device; a daemon runs through unplugs
// and wants its times on the wall clock, so our recordings add comments
// that hid-tools skip:
//
//   # plugged at T                  before each R: block: the device was (re)opened at T
//   # start T (...)                 before the first E: line: E: 000000.000000 is T
//   # unplugged at T: WHY           the device went away at T (a read failed)
//   # end at T                      the recording stopped with the device still open
//
// T is the wall-clock time in seconds since the Unix epoch with six digits
// of microseconds. Each (re)open writes the descriptor block again: a
// device plugged in again may be another one. hid-replay, which knows one
// block per device, takes the last block's descriptor for every E: line.
//
// Worked example: a Gravis GamePad Pro (tests/hid_test_devices.hpp, no
// report ids; firmware_protocol/hid_report.hpp's worked example) on a uhid
// Bluetooth bus, opened, reporting x -1, y +1, buttons 1, 3 and 10 at
// 8 ms, unplugged, plugged in again, then the daemon stopped:
//
//   # rise-hild hid recording v1: source 'pad'; hid-recorder's format, see hil/io/hid_recording.hpp
//   # plugged at 1700000000.100000
//   R: 51 05 01 09 05 a1 01 05 01 09 01 a1 00 09 30 09 31 15 00 26 ff 00 75 08 95 02 81 02 c0 05 09
//         19 01 29 0a 15 00 25 01 75 01 95 0a 81 02 95 01 75 06 81 01 c0   (one line in the file)
//   N: Gravis GamePad Pro (uhid)
//   I: 5 0428 4001
//   # start 1700000000.250000 (the wall-clock time of E: 000000.000000)
//   E: 000000.000000 4 7f 7f 00 00
//   E: 000000.008000 4 00 ff 05 02
//   # unplugged at 1700000001.000000: /dev/hidraw0: read failed (device gone)
//   # plugged at 1700000001.500000
//   R: 51 05 01 ... c0   (as above)
//   N: Gravis GamePad Pro (uhid)
//   I: 5 0428 4001
//   E: 000001.300000 4 7f 7f 00 00
//   # end at 1700000002.000000
//
// Read back: a plug at 1700000000.100000, reports at ...0.250000 and
// ...0.258000 (x = 0x00, y = 0xff, buttons 0x05 0x02: bits 0, 2 and 9), an
// unplug at ...1.000000, a plug at ...1.500000, a report at ...1.550000,
// the end at ...2.000000.
//
// Times read back are on the file's clock: µs since the Unix epoch when
// the file has a `# start` line (or no E: line at all, so that only the
// comments' times are there), otherwise µs since its first report
// (hid-tools' own files), the comments' times then unused.

#include <atomic>
#include <cstdint>
#include <fstream>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "hil/io/input_device.hpp"
#include "hil/io/record_file.hpp"

namespace rise::hil::io {

/// One thing a recording says happened to its device.
struct HidRecordingRecord {
  enum class Kind : uint8_t {
    Plug,    ///< opened: `bytes` is the descriptor, `identity` its N:/P:/I:
    Report,  ///< an input report: `bytes`
    Unplug,  ///< the device went away
    End,     ///< the recording stopped
  };
  Kind kind = Kind::Report;
  int64_t time_us = 0;  ///< on the file's clock (see above)
  int line = 0;         ///< 1-based line of its E:, R: or comment
  std::vector<uint8_t> bytes;
  HidIdentity identity;
};

/// Appends `T` as the comments write it, "1700000000.250000"; `width` pads
/// the seconds with zeros ("000001.300000" for an E: line with 6). No
/// allocation when `out` has the room.
void append_hid_time(std::string& out, int64_t us, int width = 0);

/// Appends an E: line, "E: 000000.008000 4 00 ff 05 02", for a report
/// `since_first_us` after the file's first. No allocation when `out` has
/// the room (18 + 3 bytes per report byte): cyclic-path safe.
void append_hid_event(std::string& out, int64_t since_first_us, std::span<const uint8_t> report);

/// Writes a recording: each call writes its lines (and flushes at least
/// every 100 ms, record_file.hpp). A failed write (a full disk) is counted
/// in errors(), never thrown. From one thread at a time; the counts from any.
class HidRecordingWriter {
 public:
  /// Creates or truncates `path` and writes the header comment naming
  /// `source`. Throws std::runtime_error "PATH: cannot create the HID
  /// recording".
  HidRecordingWriter(const std::string& path, std::string_view source);

  /// `# plugged at T` and the device block (R:, N:, P: when `identity` has
  /// a phys, I:). Allocates only while the line buffer grows to the
  /// descriptor's length.
  void plug(int64_t epoch_us, std::span<const uint8_t> descriptor, const HidIdentity& identity);
  /// An E: line; the first one of the file also writes `# start T`. No
  /// allocation, no throw: cyclic-path safe.
  void report(int64_t epoch_us, std::span<const uint8_t> report);
  /// `# unplugged at T: WHY` (WHY may be empty). No throw.
  void unplug(int64_t epoch_us, std::string_view why);
  /// `# end at T`. No throw.
  void end(int64_t epoch_us);

  /// Reports written, and writes or flushes that failed. Thread-safe.
  int64_t reports() const { return reports_; }
  int64_t errors() const { return file_.errors(); }

 private:
  void mark(std::string_view what, int64_t epoch_us, std::string_view why);

  RecordFile file_;
  std::string line_;
  bool started_ = false;
  int64_t start_us_ = 0;
  std::atomic<int64_t> reports_{0};
};

/// Reads a recording, record by record.
class HidRecordingReader {
 public:
  /// Opens and checks the whole file, so that next() meets no bad line.
  /// Throws std::runtime_error "PATH: cannot open the HID recording",
  /// "PATH:LINE: KEY: what" for a line that is not hid-recorder's (a
  /// length that does not match its bytes, a time without six digits of
  /// microseconds, an E: line before any R:), or "PATH: no 'R:' descriptor
  /// line: not a hid-recorder file". Not for the cyclic path.
  explicit HidRecordingReader(const std::string& path);

  /// The next record of device 0, false at the end. A Plug's descriptor
  /// comes with the N:, P: and I: lines around its R:. No throw; no
  /// allocation once `record.bytes` holds the largest report (a Plug's
  /// descriptor and name allocate).
  bool next(HidRecordingRecord& record);
  /// Back to the first record. No throw.
  void rewind();

  const std::string& path() const { return path_; }
  /// True when times are µs since the Unix epoch (the file has `# start`,
  /// or no report); false: µs since the first report.
  bool epoch_clock() const { return epoch_; }
  /// What the check found: E: lines and R: blocks of device 0.
  int64_t reports() const { return reports_; }
  int64_t plugs() const { return plugs_; }

 private:
  // One record (Check: every line is checked and an error thrown; else a
  // bad line is skipped).
  enum class Mode { Check, Play };
  bool step(HidRecordingRecord& record, Mode mode);
  // What a line does to the record being read: nothing more (Next), it is
  // complete (Emit), it ends the R: block being read (EndBlock: the block's
  // Plug is complete, the line is acted on next) or begins one of device 0.
  enum class Action { Next, Emit, EndBlock, StartBlock };
  Action read_mark(std::string_view line, HidRecordingRecord& record, Mode mode, bool in_block);  // a # line
  Action read_line(std::string_view line, HidRecordingRecord& record, Mode mode, bool in_block);  // a KEY: line
  Action read_identity(std::string_view rest, Mode mode);                                        // I: bus vid pid
  Action read_event(std::string_view rest, HidRecordingRecord& record, Mode mode);               // E: time length bytes
  // The Plug of the R: block that began at block_line; true.
  bool emit_plug(HidRecordingRecord& record, int block_line);
  // A line that is not hid-recorder's: an error while checking; when
  // playing (the file changed since), it is left out.
  void bad(Mode mode, std::string_view key, std::string_view what) const;
  void restart();

  std::string path_;
  std::ifstream in_;
  std::string text_;
  bool held_ = false;  // text_ holds a line not yet acted on
  int line_ = 0;
  int device_ = 0;    // the D: index the lines belong to
  bool plugged_ = false;  // a block of device 0 has been seen
  bool have_plug_time_ = false;
  int64_t plug_time_us_ = 0;
  HidIdentity pending_identity_;  // N:/P:/I: lines before their R:
  int64_t last_us_ = 0;
  // What the check found.
  bool epoch_ = false;
  bool start_seen_ = false;
  int64_t start_us_ = 0;
  int64_t reports_ = 0;
  int64_t plugs_ = 0;
};

/// True when the first line of `path` that is neither blank nor a comment
/// is an R: or D: line (hid-recorder's first). Does not throw.
bool looks_like_hid_recording(const std::string& path);

}  // namespace rise::hil::io
