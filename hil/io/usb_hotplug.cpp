#include "hil/io/usb_hotplug.hpp"

#include <libusb.h>

#include <chrono>

namespace rise::hil::io {
namespace {

int LIBUSB_CALL on_hotplug(libusb_context*, libusb_device*, libusb_hotplug_event, void* user_data) {
  static_cast<UsbHotplug*>(user_data)->notify_arrival();
  return 0;  // stay registered
}

}  // namespace

UsbHotplug::UsbHotplug(uint16_t vendor_id, uint16_t product_id) {
  libusb_context* context = nullptr;
  if (const int rc = libusb_init(&context); rc != LIBUSB_SUCCESS) {
    error_ = std::string("libusb_init: ") + libusb_error_name(rc);
    return;
  }
  if (libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG) == 0) {
    error_ = "libusb has no hot-plug support here";
    libusb_exit(context);
    return;
  }
  // Arrivals only: a departure shows as a failed read of the open device.
  if (const int rc = libusb_hotplug_register_callback(context, LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED,
                                                      LIBUSB_HOTPLUG_NO_FLAGS, vendor_id, product_id,
                                                      LIBUSB_HOTPLUG_MATCH_ANY, on_hotplug, this, &handle_);
      rc != LIBUSB_SUCCESS) {
    error_ = std::string("libusb_hotplug_register_callback: ") + libusb_error_name(rc);
    libusb_exit(context);
    return;
  }
  context_ = context;
  events_ = std::thread([this] { run_events(); });
}

UsbHotplug::~UsbHotplug() {
  if (!context_) return;
  stop_ = true;
  // Deregistering wakes the event thread; it also looks at stop_ every 100 ms.
  libusb_hotplug_deregister_callback(context_, handle_);
  events_.join();
  libusb_exit(context_);
}

void UsbHotplug::run_events() {
  while (!stop_) {
    timeval tv{0, 100000};
    libusb_handle_events_timeout_completed(context_, &tv, nullptr);
  }
}

void UsbHotplug::notify_arrival() noexcept {
  ++arrivals_;
  try {
    std::lock_guard lock(mutex_);  // so a waiter between its check and its wait cannot miss it
  } catch (...) {
  }
  woken_.notify_all();
}

bool UsbHotplug::wait_for_arrival(int timeout_ms) {
  try {
    std::unique_lock lock(mutex_);
    const bool arrived = woken_.wait_for(lock, std::chrono::milliseconds(timeout_ms),
                                         [this] { return arrivals_.load() != waited_; });
    if (arrived) waited_ = arrivals_.load();
    return arrived;
  } catch (...) {
    return false;
  }
}

}  // namespace rise::hil::io
