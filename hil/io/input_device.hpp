#pragma once

// A HID input device as the bridge's HID loop sees it: a report descriptor
// at each (re)open, input reports read with a timeout, output reports
// written, and, while it is away, a wait for it to come back. Two backends,
// picked by URL in open_input_device():
//
//   hid://VID:PID[?serial=S][&name=TEXT][&interface=N]   a device through hidapi (hid_device.hpp)
//   replay://FILE.hid[?speed=X][&loop=N][&start=S][&stop=S][&fast=1]
//                                                         a hid-recorder file (hid_replay_device.hpp)
//
// The bridge cannot tell one from the other, so a replay runs the same
// decode, mapping, safety and fault paths as the device did.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "hil/io/can_bus.hpp"

namespace rise::hil::io {

/// Largest input report read (hidraw caps reports at 4096 bytes).
constexpr std::size_t max_hid_report_bytes = 4096;

/// Who a HID device says it is, as hid-recorder writes it: `N:` the name
/// (HIDIOCGRAWNAME, sysfs HID_NAME), `P:` the physical path (HIDIOCGRAWPHYS,
/// HID_PHYS; empty when unknown), `I:` bus, vendor and product.
struct HidIdentity {
  std::string name;
  std::string phys;
  uint32_t bus = 0;  ///< linux/input.h BUS_*: 3 USB, 5 Bluetooth, 6 virtual
  uint16_t vendor_id = 0;
  uint16_t product_id = 0;
  bool operator==(const HidIdentity&) const = default;
};

/// One HID input device. Used from one thread (the bridge's source thread);
/// the counters of a backend may be read from any.
class InputDevice {
 public:
  virtual ~InputDevice() = default;

  /// Opens the device (a closed one; an open one is closed first). Ok, with
  /// report_descriptor() and identity() set; Disconnected when it is not
  /// there; Error when it is but cannot be opened. Allocates: call from the
  /// source's thread at plug time, not per report. Does not throw.
  virtual IoStatus reopen() = 0;
  virtual void close() = 0;
  virtual bool is_open() const = 0;

  /// Reads one input report (with its id byte when the descriptor uses ids)
  /// into `report`, waiting up to timeout_ms: Ok with `length` set, Timeout,
  /// or Disconnected (the device went away and is closed). No allocation,
  /// no throw: cyclic-path safe.
  virtual IoStatus read(std::span<uint8_t> report, std::size_t& length, int timeout_ms) = 0;
  /// Writes an output report (first byte: report id, 0 when ids are unused).
  /// No allocation, no throw.
  virtual IoStatus write(std::span<const uint8_t> report) = 0;

  /// While closed: waits up to timeout_ms for the device to arrive; true
  /// when it did (reopen now). No allocation, no throw.
  virtual bool wait_for_arrival(int timeout_ms) = 0;
  /// Whether wait_for_arrival() learns of an arrival as it happens; if not,
  /// hotplug_error() says why and the caller enumerates periodically.
  virtual bool hotplug_active() const = 0;
  virtual const std::string& hotplug_error() const = 0;

  /// The raw report descriptor of the open device (empty before the first open).
  virtual const std::vector<uint8_t>& report_descriptor() const = 0;
  virtual const HidIdentity& identity() const = 0;
  /// The URL the device was made from.
  virtual const std::string& url() const = 0;
  virtual std::string last_error() const = 0;
};

/// True for the URLs a HID source takes: hid:// and replay://.
bool is_input_device_url(std::string_view url);

/// The device of a hid source's URL: a HidDevice for hid://, a
/// HidReplayDevice for replay://. Does not open it (the bridge does). Throws
/// std::invalid_argument naming the URL and what is wrong with it, and
/// std::runtime_error "FILE:LINE: what" for a replay file that is missing
/// or not a hid-recorder file. Not for the cyclic path.
std::unique_ptr<InputDevice> open_input_device(const std::string& url);

}  // namespace rise::hil::io
