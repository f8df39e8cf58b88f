#pragma once

// An InputDevice that records what the device it wraps did, in
// hid-recorder's format (hid_recording.hpp): each (re)open as a plug with
// its descriptor block, each input report read as an E: line stamped with
// the wall-clock time read() returned it (when the bridge decoded it, which
// a verified replay must reproduce), each loss as an unplug, and, when it
// is destroyed with the device open, the end. Output reports are passed on
// and not recorded (hid-recorder has no line for them).

#include <memory>
#include <string>

#include "hil/io/hid_recording.hpp"
#include "hil/io/input_device.hpp"

namespace rise::hil::io {

class RecordingInputDevice final : public InputDevice {
 public:
  /// Records `device` into `path` (created or truncated) under the name
  /// `source`. Throws std::runtime_error if the file cannot be created.
  RecordingInputDevice(std::unique_ptr<InputDevice> device, const std::string& path, std::string source);
  ~RecordingInputDevice() override;

  /// Each passes the call on and writes what it did; a failed write (disk
  /// full) is counted in write_errors(), never thrown. read() allocates
  /// nothing for a report: cyclic-path safe; an unplug's line allocates.
  IoStatus reopen() override;
  void close() override;
  IoStatus read(std::span<uint8_t> report, std::size_t& length, int timeout_ms) override;

  bool is_open() const override { return device_->is_open(); }
  IoStatus write(std::span<const uint8_t> report) override { return device_->write(report); }
  bool wait_for_arrival(int timeout_ms) override { return device_->wait_for_arrival(timeout_ms); }
  bool hotplug_active() const override { return device_->hotplug_active(); }
  const std::string& hotplug_error() const override { return device_->hotplug_error(); }
  const std::vector<uint8_t>& report_descriptor() const override { return device_->report_descriptor(); }
  const HidIdentity& identity() const override { return device_->identity(); }
  const std::string& url() const override { return device_->url(); }
  std::string last_error() const override { return device_->last_error(); }

  /// The device recorded (tests reach a backend's own counters through it).
  InputDevice& device() { return *device_; }
  /// Input reports written, and writes or flushes that failed. Thread-safe.
  int64_t reports_recorded() const { return writer_.reports(); }
  int64_t write_errors() const { return writer_.errors(); }

 private:
  std::unique_ptr<InputDevice> device_;
  HidRecordingWriter writer_;
};

}  // namespace rise::hil::io
