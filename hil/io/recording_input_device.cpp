#include "hil/io/recording_input_device.hpp"

#include "hil/io/posix_io.hpp"
#include "msgs/clock.hpp"

namespace rise::hil::io {

RecordingInputDevice::RecordingInputDevice(std::unique_ptr<InputDevice> device, const std::string& path,
                                           std::string source)
    : device_(std::move(device)), writer_(path, source) {}

RecordingInputDevice::~RecordingInputDevice() {
  if (device_->is_open()) writer_.end(msgs::wall_us());
}

IoStatus RecordingInputDevice::reopen() {
  // Reopening an open device closes it first: an unplug, then the plug.
  if (device_->is_open()) writer_.unplug(msgs::wall_us(), "reopened");
  const IoStatus st = device_->reopen();
  if (st == IoStatus::Ok) writer_.plug(msgs::wall_us(), device_->report_descriptor(), device_->identity());
  return st;
}

void RecordingInputDevice::close() {
  if (device_->is_open()) writer_.unplug(msgs::wall_us(), "closed");
  device_->close();
}

IoStatus RecordingInputDevice::read(std::span<uint8_t> report, std::size_t& length, int timeout_ms) {
  const bool was_open = device_->is_open();
  const IoStatus st = device_->read(report, length, timeout_ms);
  if (st == IoStatus::Ok) {
    writer_.report(msgs::wall_us(), std::span<const uint8_t>(report.data(), length));
  } else if (st == IoStatus::Disconnected && was_open) {
    writer_.unplug(msgs::wall_us(), device_->last_error());
  }
  return st;
}

}  // namespace rise::hil::io
