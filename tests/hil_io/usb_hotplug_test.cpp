// UsbHotplug on the host: libusb may or may not offer hot-plug here (a
// container without udev or USB); either way waiting works and nothing
// throws. A real arrival needs a USB device: see tests/vcan/.

#include <catch2/catch.hpp>

#include <chrono>
#include <thread>

#include "hil/io/hid_device.hpp"
#include "hil/io/usb_hotplug.hpp"

namespace io = rise::hil::io;
using Clock = std::chrono::steady_clock;

namespace {
int64_t ms_since(Clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - t).count();
}
}  // namespace

TEST_CASE("usb hotplug either watches or says why not, and waits either way", "[hil_io]") {
  // pid.codes' test VID:PID: no such device is plugged in here.
  io::UsbHotplug hotplug(0x1209, 0x0001);
  CHECK(hotplug.available() == hotplug.error().empty());
  if (!hotplug.available()) WARN("libusb hot-plug unavailable here: " << hotplug.error());
  const auto t0 = Clock::now();
  CHECK_FALSE(hotplug.wait_for_arrival(30));
  CHECK(ms_since(t0) >= 25);
  CHECK(ms_since(t0) < 2000);
  CHECK(hotplug.arrivals() == 0);
}

TEST_CASE("usb hotplug wakes a waiting thread at an arrival, once per arrival", "[hil_io]") {
  io::UsbHotplug hotplug(0x1209, 0x0001);
  SECTION("an arrival before the wait is not lost") {
    hotplug.notify_arrival();
    CHECK(hotplug.wait_for_arrival(0));
    CHECK_FALSE(hotplug.wait_for_arrival(0));  // consumed
  }
  SECTION("an arrival during the wait ends it at once") {
    const auto t0 = Clock::now();
    std::thread other([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      hotplug.notify_arrival();
    });
    CHECK(hotplug.wait_for_arrival(10000));
    other.join();
    CHECK(ms_since(t0) < 5000);
    CHECK(hotplug.arrivals() == 1);
  }
}

TEST_CASE("usb hotplug stops its event thread promptly", "[hil_io]") {
  const auto t0 = Clock::now();
  for (int i = 0; i < 3; ++i) {
    io::UsbHotplug hotplug(0x046d, 0xc215);
    CHECK_FALSE(hotplug.wait_for_arrival(1));
  }
  CHECK(ms_since(t0) < 3000);
}

TEST_CASE("hid device reports whether USB hot-plug watches for it", "[hil_io]") {
  io::HidDevice device("hid://1209:0001");
  CHECK(device.hotplug_active() == device.hotplug_error().empty());
  device.notify_arrival();
  CHECK(device.wait_for_arrival(0));
  CHECK_FALSE(device.is_open());
}
