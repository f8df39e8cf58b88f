#pragma once

// A hid source read through evdev:// (hil/io/evdev_device.hpp): a gamepad
// the kernel already drives. Each (re)open names the device's signals
// (hil/io/evdev_signals.hpp: the kernel's codes and, with `mapping: sdl`,
// SDL's names from the line of the device's GUID) and binds the panel's
// controls to them; each frame of events (SYN_REPORT) gives the panel every
// signal's value; while nothing happens the open device keeps the source
// fresh (events come only on change). A lost device (ENODEV) is reported at
// once and looked for again when a node under /dev/input appears (inotify)
// and every enumeration period. The panel's rumble, when bound to
// `signal: ff_rumble`, plays through EV_FF (FF_RUMBLE, both motors).

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hil/io/evdev_device.hpp"
#include "hil/io/evdev_signals.hpp"
#include "hil/source_transport.hpp"

namespace rise::hil {

class EvdevSource final : public SourceTransport {
 public:
  explicit EvdevSource(std::unique_ptr<io::EvdevDevice> device);

  bool is_open() const override { return device_->is_open(); }
  /// Opens the device and binds the controls; a bound name the device
  /// lacks (or an SDL name without a line for its GUID) keeps the source
  /// failsafe with the reason until the next plug.
  io::IoStatus reopen(SourcePanel& panel) override;
  std::string last_error() const override { return device_->last_error(); }
  ConnectionPolicy connection_policy() const override;
  bool wait_while_closed(int timeout_ms) override { return device_->wait_for_arrival(timeout_ms); }
  io::IoStatus receive(SourcePanel& panel, int timeout_ms) override;
  bool shows_feedback() const override { return rumble_; }
  FeedbackPolicy feedback_policy() const override;
  io::IoStatus send_feedback(SourcePanel& panel, const FeedbackRequest& request, const PanelSnapshot& snapshot,
                             bool resend) override;
  /// Neither wire faults nor a recorder know evdev events: left as it is.
  void decorate(IoDecorator&) override {}

  const io::EvdevDevice& device() const { return *device_; }

 private:
  std::string bind_sdl(SourcePanel& panel);
  void check_feedback(SourcePanel& panel);

  std::unique_ptr<io::EvdevDevice> device_;
  std::optional<io::EvdevSignals> signals_;
  std::vector<double> values_;
  bool rumble_ = false;
  bool opened_ = false;  // reopened: the next receive() gives the panel the state read at open
  std::optional<float> last_rumble_;
};

}  // namespace rise::hil
