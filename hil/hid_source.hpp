#pragma once

// A HID source's transport (hid) for the bridge's source loop: each (re)open
// binds the device's report descriptor to the panel's signal names, each
// input report goes to the panel, and the LEDs' output reports are written
// on (re)open, when the request changes and, checked every feedback period,
// when the panel's own LEDs (fault, estop) change. A lost device is looked
// for by hot-plug (ConnectionPolicy::enumerate).

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "firmware_protocol/hid_report.hpp"
#include "hil/io/input_device.hpp"
#include "hil/source_transport.hpp"

namespace rise::hil {

class HidSource final : public SourceTransport {
 public:
  /// `device` (a HidDevice or a HidReplayDevice) is source `source` of `definition`.
  HidSource(std::unique_ptr<io::InputDevice> device, const panels::PanelDefinition& definition, std::size_t source);

  bool is_open() const override { return device_->is_open(); }
  /// Opens the device; a descriptor without a bound name keeps the source
  /// failsafe with the mapper's reason until the next plug. Notes each LED
  /// the device cannot show.
  io::IoStatus reopen(SourcePanel& panel) override;
  std::string last_error() const override { return device_->last_error(); }
  ConnectionPolicy connection_policy() const override;
  bool wait_while_closed(int timeout_ms) override { return device_->wait_for_arrival(timeout_ms); }
  io::IoStatus receive(SourcePanel& panel, int timeout_ms) override;
  /// Once open, when the device has an output report for an LED or rumble of the source.
  bool shows_feedback() const override { return encoder_.has_value(); }
  FeedbackPolicy feedback_policy() const override;
  io::IoStatus send_feedback(SourcePanel& panel, const FeedbackRequest& request, const PanelSnapshot& snapshot,
                             bool resend) override;
  void decorate(IoDecorator& decorator) override { device_ = decorator.wrap(std::move(device_)); }

  /// The device, as decorated.
  const io::InputDevice& device() const { return *device_; }

 private:
  std::unique_ptr<io::InputDevice> device_;
  bool has_outputs_ = false;  // the definition binds an LED or a rumble to the device
  std::optional<firmware_protocol::HidOutputEncoder> encoder_;
  std::vector<std::vector<uint8_t>> last_written_;
  std::array<uint8_t, io::max_hid_report_bytes> report_{};
};

}  // namespace rise::hil
