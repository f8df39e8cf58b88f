#pragma once

// A USB/Bluetooth HID device (joystick, gamepad, button box) through hidapi's
// hidraw backend, opened from a URL:
//
//   hid://VID:PID[?serial=S][&name=TEXT][&interface=N]
//
// VID and PID in hex (`hid://0428:4001`); `serial` matches the serial number
// exactly, `name` is a substring of the product string, `interface` the USB
// interface number. Hot-plug: reopen() enumerates; while the device is away
// the bridge waits in wait_for_arrival(), which libusb's hot-plug callback
// for the VID:PID ends at once when a USB device arrives (UsbHotplug), and
// otherwise enumerates every period (Bluetooth and uhid devices, no libusb).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "hil/io/can_bus.hpp"
#include "hil/io/input_device.hpp"
#include "hil/io/posix_io.hpp"
#include "hil/io/usb_hotplug.hpp"

struct hid_device_;

namespace rise::hil::io {

struct HidUrl {
  uint16_t vendor_id = 0;
  uint16_t product_id = 0;
  std::string serial;     ///< empty: any
  std::string name;       ///< substring of the product string; empty: any
  int interface = -1;     ///< -1: any
};

/// Parses a hid:// URL; nullopt (and `error` set when given) if malformed.
/// Four hex digits at most (a USB vendor or product id), nothing else; nullopt otherwise.
std::optional<uint16_t> parse_hex16(std::string_view text);

std::optional<HidUrl> parse_hid_url(std::string_view url, std::string* error = nullptr);

class HidDevice final : public InputDevice {
 public:
  /// Does not open: call reopen(). Throws std::invalid_argument for a bad URL.
  explicit HidDevice(const std::string& url);
  ~HidDevice() override;
  HidDevice(const HidDevice&) = delete;
  HidDevice& operator=(const HidDevice&) = delete;

  /// Enumerates the HID devices, opens the first that matches the URL and
  /// reads its report descriptor from sysfs
  /// (/sys/class/hidraw/hidrawN/device/report_descriptor: hidapi 0.13 has no
  /// hid_get_report_descriptor) and its identity from the uevent beside it
  /// (HID_NAME, HID_PHYS, HID_ID). Ok, or Disconnected when none matches,
  /// Error when it matches but cannot be opened (permissions). Allocates:
  /// call from the source's thread, not at the publish rate.
  IoStatus reopen() override;
  void close() override;
  bool is_open() const override { return device_ != nullptr; }

  /// Reads one input report (with its id byte when the descriptor uses ids)
  /// into `report`, waiting up to timeout_ms. Ok with `length` set, Timeout,
  /// or Disconnected (the device went away; the handle is closed). No
  /// allocation, no throw.
  IoStatus read(std::span<uint8_t> report, std::size_t& length, int timeout_ms) override;

  /// Writes an output report (first byte: report id, 0 when ids are unused).
  IoStatus write(std::span<const uint8_t> report) override;

  /// Waits up to timeout_ms for the URL's VID:PID to arrive on USB; true
  /// when it did (enumerate now). Without libusb hot-plug it only waits.
  /// No allocation, no throw: cyclic-path safe.
  bool wait_for_arrival(int timeout_ms) override { return hotplug_->wait_for_arrival(timeout_ms); }
  /// Ends a wait_for_arrival() as an arrival does (for callers who learn of
  /// one otherwise, and tests). Thread-safe.
  void notify_arrival() { hotplug_->notify_arrival(); }
  /// Whether libusb's hot-plug callbacks watch for the device; if not,
  /// hotplug_error() says why.
  bool hotplug_active() const override { return hotplug_->available(); }
  const std::string& hotplug_error() const override { return hotplug_->error(); }

  /// The raw report descriptor of the open device (empty when closed).
  const std::vector<uint8_t>& report_descriptor() const override { return descriptor_; }
  /// The open device's name, phys, bus and ids (the URL's VID:PID and
  /// hidapi's product string where sysfs has no uevent).
  const HidIdentity& identity() const override { return identity_; }
  /// The hidraw node of the open device ("/dev/hidraw0").
  const std::string& path() const { return path_; }
  const std::string& url() const override { return url_text_; }
  const HidUrl& address() const { return url_; }
  std::string last_error() const override { return error_.get(); }

 private:
  std::string url_text_;
  HidUrl url_;
  std::unique_ptr<UsbHotplug> hotplug_;
  hid_device_* device_ = nullptr;
  std::vector<uint8_t> descriptor_;
  HidIdentity identity_;
  std::string path_;
  detail::ErrorText error_;
};

}  // namespace rise::hil::io
