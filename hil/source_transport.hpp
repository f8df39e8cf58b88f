#pragma once

// One source's transport as the bridge's source loop drives it, whatever
// carries it: a CAN bus (rise-can-v1, dbc: can_source.hpp), a Modbus link
// (rise-modbus-v1, modbus: modbus_source.hpp) or a HID device (hid:
// hid_source.hpp). Each adapts its io class (io::CanBus, io::ModbusLink,
// io::InputDevice) to these calls; the bridge runs one loop for all of them
// (bridge.cpp): reopen when due, read or poll the inputs into the panel,
// write the feedback when it is due (source_schedule.hpp). Every call but
// decorate() comes from the source's own thread, and none throws;
// io::IoStatus is the one status of every call.

#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include "hil/feedback.hpp"
#include "hil/io/can_bus.hpp"
#include "hil/io/input_device.hpp"
#include "hil/io/modbus_link.hpp"
#include "hil/panel_mapper.hpp"
#include "hil/source_panel.hpp"

namespace rise::hil {

/// How the bridge judges a source's connection by its transport, and brings
/// a closed transport back.
struct ConnectionPolicy {
  /// The source is up while its transport is open (CAN, HID). False for a
  /// transport whose source is up only once the loop reopened it or the
  /// peer answered (a Modbus link, opened before the loop starts: receive()
  /// marks it up at each answered poll).
  bool up_while_open = true;
  /// A closed transport is a lost one: its source is marked down at once
  /// (CAN, HID). False for a transport that closes itself to restart
  /// cleanly (a Modbus link after a timeout, so that a late answer is not
  /// taken for the next one): it is reopened at once and marked down only
  /// when that fails, so one lost answer is judged by the source's age.
  bool closed_is_down = true;
  /// Hot-plug (HID): looked for every BridgeSettings::hid_enumerate_ms, and
  /// at once when wait_while_closed() sees it arrive, rather than with the
  /// back-off of reopen_min_ms..reopen_max_ms.
  bool enumerate = false;
  /// With `enumerate`: why arrivals are not seen as they happen ("no USB
  /// hot-plug (...)"), for a note; empty when they are.
  std::string unseen_arrivals;
};

/// When the bridge builds a source's feedback, and whether an unchanged one
/// goes out again (FeedbackSchedule).
struct FeedbackPolicy {
  /// Built after each poll and only then (a polled transport writes between
  /// its polls); otherwise when it was never written since the transport
  /// opened, the feedback period elapsed, or the request changed.
  bool after_each_poll = false;
  /// Written again unchanged every feedback period (a console that expects
  /// its feedback cyclically); otherwise only when it changed.
  bool repeat = true;
};

/// Puts a decorator (wire faults, a recorder) around a transport's io
/// object, whichever kind it is: SourceTransport::decorate() calls the
/// overload of its kind and keeps what it returns.
class IoDecorator {
 public:
  virtual ~IoDecorator() = default;
  virtual std::unique_ptr<io::CanBus> wrap(std::unique_ptr<io::CanBus> bus) = 0;
  virtual std::unique_ptr<io::ModbusLink> wrap(std::unique_ptr<io::ModbusLink> link) = 0;
  virtual std::unique_ptr<io::InputDevice> wrap(std::unique_ptr<io::InputDevice> device) = 0;
};

class SourceTransport {
 public:
  virtual ~SourceTransport() = default;

  virtual bool is_open() const = 0;
  /// Opens the closed transport, once (the bridge does the back-off), and
  /// binds what the panel learns at open (a HID device's descriptor). Ok
  /// when it is open. Allocates.
  virtual io::IoStatus reopen(SourcePanel& panel) = 0;
  /// Why the transport is down: the OS's or the library's last error.
  virtual std::string last_error() const = 0;
  virtual ConnectionPolicy connection_policy() const { return {}; }
  /// While closed: waits up to timeout_ms; true when the device arrived
  /// (reopen now). This one sleeps and says no.
  virtual bool wait_while_closed(int timeout_ms) {
    std::this_thread::sleep_for(std::chrono::milliseconds(timeout_ms));
    return false;
  }

  /// Takes the next input into the panel, waiting up to timeout_ms: Ok when
  /// one was taken (a frame, a report, a poll made on a link still open,
  /// whatever it answered), Timeout when none came (or no poll was due),
  /// Disconnected when the transport was lost (the bridge marks the source
  /// down with last_error() and publishes that at once).
  virtual io::IoStatus receive(SourcePanel& panel, int timeout_ms) = 0;

  /// Whether this source shows feedback (a dbc device's database has no
  /// feedback frames; a HID device may have no output report).
  virtual bool shows_feedback() const = 0;
  virtual FeedbackPolicy feedback_policy() const { return {}; }
  /// Builds the feedback for `request` and the panel's `snapshot` and
  /// writes it when `resend` or when it differs from what was last written.
  /// Ok when written or unchanged; a failure is tried again at the next check.
  virtual io::IoStatus send_feedback(SourcePanel& panel, const FeedbackRequest& request,
                                     const PanelSnapshot& snapshot, bool resend) = 0;

  /// Puts `decorator` around the io object. Before the bridge starts.
  virtual void decorate(IoDecorator& decorator) = 0;
};

}  // namespace rise::hil
