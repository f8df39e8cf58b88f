#pragma once

// Arrival of one USB device (VID:PID) through libusb's hot-plug callbacks
// (libusb 1.0.16+, libusb_hotplug_register_callback). The HID source loop
// waits on it instead of sleeping while its device is away, so a replugged
// USB joystick is enumerated at once rather than at the next periodic
// enumeration, which stays as the fallback: where libusb has no hot-plug
// support or cannot start (no USB in a container), and for HID devices that
// are no USB devices (Bluetooth, uhid), which libusb never sees.
//
// libusb runs its callbacks on an event thread of this object's own
// context; the callback only counts and wakes the waiter.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>

struct libusb_context;

namespace rise::hil::io {

class UsbHotplug {
 public:
  /// Starts watching for vendor_id:product_id. Never throws (except
  /// std::bad_alloc): without hot-plug support available() is false and
  /// error() says why; waiting then only waits.
  UsbHotplug(uint16_t vendor_id, uint16_t product_id);
  ~UsbHotplug();
  UsbHotplug(const UsbHotplug&) = delete;
  UsbHotplug& operator=(const UsbHotplug&) = delete;

  /// Whether libusb's callbacks watch for the device.
  bool available() const { return context_ != nullptr; }
  /// Why not ("libusb_init: LIBUSB_ERROR_OTHER", "libusb has no hot-plug
  /// support here"); empty when available.
  const std::string& error() const { return error_; }

  /// Waits up to timeout_ms for an arrival not yet waited for; true when one
  /// came. No allocation, no throw: cyclic-path safe.
  bool wait_for_arrival(int timeout_ms);
  /// Counts an arrival and wakes the waiter: what the libusb callback does;
  /// also for callers who learn of an arrival otherwise. Thread-safe.
  void notify_arrival() noexcept;
  /// Arrivals so far.
  uint64_t arrivals() const { return arrivals_.load(); }

 private:
  void run_events();

  libusb_context* context_ = nullptr;
  int handle_ = 0;  // libusb_hotplug_callback_handle
  std::string error_;
  std::atomic<uint64_t> arrivals_{0};
  uint64_t waited_ = 0;  // arrivals already returned by wait_for_arrival
  std::mutex mutex_;
  std::condition_variable woken_;
  std::atomic<bool> stop_{false};
  std::thread events_;
};

}  // namespace rise::hil::io
