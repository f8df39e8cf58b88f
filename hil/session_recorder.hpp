#pragma once

// rise-hild --record DIR: the raw traffic of every source in the format its
// ecosystem reads, and what the daemon published, side by side in DIR:
//   <source>.log           CAN: candump -l log (hil/io/recording_bus.hpp), each
//                          received frame stamped with the time the daemon read it
//   <source>.modbus.log    Modbus: transaction trace (hil/io/modbus_trace.hpp)
//   <source>.hid           HID: hid-recorder's format (hil/io/hid_recording.hpp),
//                          each report stamped with the time the daemon read it,
//                          each plug with its descriptor, each unplug
//   panel_state.lcmlog     every PanelState published, in LCM's event log
//                          format (lcm-logger's: lcm-logplayer, lcm-spy read it)
// `rise-hild verify --record-dir DIR` replays the captures against the log.
// A full disk loses records (counted, reported), never the daemon.

#include <lcm/lcm-cpp.hpp>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "hil/source_transport.hpp"
#include "hil/io/recording_bus.hpp"
#include "hil/io/recording_input_device.hpp"
#include "hil/io/recording_modbus_link.hpp"
#include "rise_msgs/PanelState.hpp"

namespace rise::hil {

class SessionRecorder {
 public:
  /// Creates `dir` (and its parents) and DIR/panel_state.lcmlog. Throws
  /// std::runtime_error naming what cannot be created.
  explicit SessionRecorder(std::string dir);
  SessionRecorder(const SessionRecorder&) = delete;
  SessionRecorder& operator=(const SessionRecorder&) = delete;

  /// Wraps a source's transport's io object so that its traffic is
  /// recorded into DIR/<name>.log (CAN), DIR/<name>.modbus.log (Modbus,
  /// `modbus_unit` on each line) or DIR/<name>.hid (HID); false when it
  /// has none of these. Throws
  /// std::runtime_error when the file cannot be created. The recorder keeps
  /// a pointer to the wrapper for its counts: call counts() only while the
  /// transport (the bridge) lives.
  bool record_source(const std::string& name, SourceTransport& transport, int modbus_unit);

  /// Writes one published message as an event at its utime on `channel`.
  /// From one thread (the publisher's). Does not throw; a failed write is
  /// counted. Allocates only while the encode buffer grows.
  void record_message(const std::string& channel, const rise_msgs::PanelState& message);

  struct Counts {
    int64_t can_frames = 0;
    int64_t modbus_lines = 0;
    int64_t hid_reports = 0;
    int64_t lcm_events = 0;
    int64_t write_errors = 0;  ///< all files together
  };
  Counts counts() const;
  /// Every file written, in the order they were created.
  const std::vector<std::string>& files() const { return files_; }
  const std::string& dir() const { return dir_; }

 private:
  class SourceRecorder;

  std::string dir_;
  std::vector<std::string> files_;
  lcm::LogFile log_;
  lcm::LogEvent event_{};
  std::vector<uint8_t> buffer_;
  std::atomic<int64_t> lcm_events_{0};
  std::atomic<int64_t> lcm_errors_{0};
  std::chrono::steady_clock::time_point last_flush_;
  std::vector<const io::RecordingBus*> buses_;
  std::vector<const io::RecordingModbusLink*> links_;
  std::vector<const io::RecordingInputDevice*> hid_devices_;
};

}  // namespace rise::hil
