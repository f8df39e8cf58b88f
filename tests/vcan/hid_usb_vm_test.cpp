// libusb hot-plug against a real USB stack. The VM's kernel (run_in_vcan_vm.sh,
// modules dummy_hcd, libcomposite, usb_f_hid, usbhid) plugs a USB HID device
// into itself: dummy_hcd is a virtual host controller wired to a virtual
// device controller, and the kernel's HID gadget function (usb_f_hid, set up
// through configfs) is the device on it: 1209:0002 with the LED test pad's
// report descriptor. usbhid binds it like any USB joystick, so hidapi finds
// a BUS_USB device with a USB parent, and libusb's udev backend sees it
// arrive once systemd-udevd relays the kernel's uevents (started here,
// stopped by PID). The gadget side is /dev/hidg0: input reports written
// there reach the host, output reports the host writes are read there.
//
// The bridge enumerates only every 60 s in this test: a re-plug that is
// found within seconds was found through libusb's arrival callback.

#include <catch2/catch.hpp>

#include <fcntl.h>
#include <poll.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <thread>

#include "process/child_process.hpp"
#include "hil/bridge.hpp"
#include "hil/io/hid_device.hpp"
#include "hil/hid_source.hpp"
#include "hil/io/usb_hotplug.hpp"
#include "panels/panel_definition.hpp"
#include "tests/hid_test_devices.hpp"

namespace io = rise::hil::io;
namespace fs = std::filesystem;
using rise::hil::Bridge;
using rise::hil::PanelSnapshot;
using Clock = std::chrono::steady_clock;

namespace {

bool wait_for(const std::function<bool()>& done, std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
  const auto deadline = Clock::now() + timeout;
  while (Clock::now() < deadline) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return done();
}

int64_t ms_since(Clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - t).count();
}

void write_file(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.close();
  INFO(path);
  REQUIRE(out.good());
}

// The device side: a configfs gadget with one HID function on the dummy
// device controller (Documentation/usb/gadget_configfs.rst,
// Documentation/usb/gadget_hid.rst).
class UsbHidGadget {
 public:
  UsbHidGadget() {
    if (!fs::exists("/sys/kernel/config/usb_gadget"))
      REQUIRE(::mount("configfs", "/sys/kernel/config", "configfs", 0, nullptr) == 0);
    REQUIRE(fs::create_directory(root_));
    write_file(root_ / "idVendor", "0x1209");  // pid.codes test VID
    write_file(root_ / "idProduct", "0x0002");
    fs::create_directories(root_ / "strings/0x409");
    write_file(root_ / "strings/0x409/manufacturer", "rise");
    write_file(root_ / "strings/0x409/product", "rise USB LED test pad");
    write_file(root_ / "strings/0x409/serialnumber", "rise-usb-1");
    fs::create_directories(root_ / "configs/c.1");
    fs::create_directories(root_ / "functions/hid.usb0");
    write_file(root_ / "functions/hid.usb0/protocol", "0");
    write_file(root_ / "functions/hid.usb0/subclass", "0");
    write_file(root_ / "functions/hid.usb0/report_length", "4");  // the longest report, id byte included
    write_file(root_ / "functions/hid.usb0/report_desc",
               std::string(std::begin(rise::test::led_pad_descriptor), std::end(rise::test::led_pad_descriptor)));
    fs::create_symlink(root_ / "functions/hid.usb0", root_ / "configs/c.1/hid.usb0");
    for (const auto& e : fs::directory_iterator("/sys/class/udc")) udc_ = e.path().filename();
    REQUIRE(!udc_.empty());
  }
  ~UsbHidGadget() {
    unplug();
    std::error_code ec;
    fs::remove(root_ / "configs/c.1/hid.usb0", ec);
    for (const char* d : {"configs/c.1", "functions/hid.usb0", "strings/0x409", ""}) fs::remove(root_ / d, ec);
  }
  UsbHidGadget(const UsbHidGadget&) = delete;
  UsbHidGadget& operator=(const UsbHidGadget&) = delete;

  void plug() { write_file(root_ / "UDC", udc_); }
  void unplug() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    std::ofstream(root_ / "UDC") << "\n";
  }
  // One input report through the interrupt IN endpoint, once the host polls.
  bool send(std::initializer_list<uint8_t> report) {
    if (!open_node()) return false;
    pollfd p{fd_, POLLOUT, 0};
    if (::poll(&p, 1, 5000) != 1) return false;
    const std::vector<uint8_t> bytes(report);
    return ::write(fd_, bytes.data(), bytes.size()) == static_cast<ssize_t>(bytes.size());
  }
  // The next output report the host wrote (empty after timeout_ms).
  std::vector<uint8_t> read_output(int timeout_ms) {
    if (!open_node()) return {};
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) != 1) return {};
    std::vector<uint8_t> bytes(64);
    const ssize_t n = ::read(fd_, bytes.data(), bytes.size());
    bytes.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
    return bytes;
  }

 private:
  bool open_node() {
    if (fd_ < 0) fd_ = ::open("/dev/hidg0", O_RDWR | O_NONBLOCK | O_CLOEXEC);
    return fd_ >= 0;
  }
  fs::path root_ = "/sys/kernel/config/usb_gadget/rise";
  std::string udc_;
  int fd_ = -1;
};

const char* usb_pad_panel =
    "panel: usb-pad\n"
    "sources:\n"
    "  - {name: pad, protocol: hid, device: 'hid://1209:0002', timeout_ms: 0}\n"
    "controls:\n"
    "  - {name: drive_x, kind: axis, signal: x, safe: 0}\n"
    "  - {name: drive_y, kind: axis, signal: y, safe: 0}\n"
    "  - {name: deadman, kind: button, signal: button_1, role: deadman, safe: false}\n"
    "feedback:\n"
    "  leds: [{name: power, signal: usage_0008_0001}, {name: lamp, signal: usage_0008_0004}]\n";

}  // namespace

TEST_CASE("a USB HID device re-plugged is reopened through libusb's arrival callback, not the enumeration period",
          "[vcan]") {
  // libusb's udev backend hears of devices from udevd, not from the kernel.
  fs::create_directories("/run");  // the VM's initramfs has none
  rise::process::ChildProcess udevd({"/lib/systemd/systemd-udevd"}, "/tmp/udevd.log");
  const bool udevd_ready = wait_for([] { return fs::exists("/run/udev/control"); });
  if (!udevd_ready) {
    std::ifstream log("/tmp/udevd.log");
    FAIL("systemd-udevd did not start: " << std::string(std::istreambuf_iterator<char>(log), {}));
  }
  UsbHidGadget gadget;
  gadget.plug();

  const auto definition = rise::panels::parse_panel_definition(usb_pad_panel, "usb_pad.yaml");
  auto source = std::make_unique<rise::hil::HidSource>(std::make_unique<io::HidDevice>("hid://1209:0002?name=LED test pad"),
                                                       definition, 0);
  const io::InputDevice& device = source->device();
  INFO("libusb: " << device.hotplug_error());
  REQUIRE(device.hotplug_active());
  std::vector<std::unique_ptr<rise::hil::SourceTransport>> transports;
  transports.push_back(std::move(source));
  rise::hil::BridgeSettings settings;
  settings.hid_enumerate_ms = 60000;
  Bridge bridge(definition, std::move(transports),
                [](const PanelSnapshot&) {}, settings);
  const auto control = [&](const char* name) { return *bridge.definition().find_control(name); };
  const auto started = Clock::now();
  bridge.start();
  CHECK(bridge.take_notes().empty());  // no "no USB hot-plug" note

  // Found by the first enumeration, or by the arrival if the kernel was still
  // binding usbhid then. Reports and LEDs as with uhid, now over usbhid.
  REQUIRE(wait_for([&] { return bridge.snapshot().sources[0].connected; }));
  WARN("USB gadget plugged -> bridge open: " << ms_since(started) << " ms");
  REQUIRE(gadget.send({0x01, 0x00, 0xFF, 0x01}));
  REQUIRE(wait_for([&] { return !bridge.snapshot().failsafe; }));
  PanelSnapshot snap = bridge.snapshot();
  CHECK(snap.controls[control("drive_x")].axis == Approx(-1.0).margin(1e-6));
  CHECK(snap.controls[control("drive_y")].axis == Approx(1.0).margin(1e-6));
  CHECK(snap.controls[control("deadman")].pressed);
  // The LEDs' output report, written on open, through the OUT endpoint.
  std::vector<uint8_t> leds = gadget.read_output(5000);
  REQUIRE(leds.size() == 2);
  CHECK(leds[0] == 0x02);
  CHECK((leds[1] & 0x01) == 0x01);  // power
  rise::hil::FeedbackRequest request;
  request.leds = {{"lamp", true}};
  bridge.set_feedback(request);
  REQUIRE(wait_for([&] {
    leds = gadget.read_output(50);
    return leds.size() == 2 && (leds[1] & 0x08) != 0;
  }));
  CHECK((leds[1] & 0x09) == 0x09);  // lamp and power

  for (int replug = 1; replug <= 2; ++replug) {
    INFO("re-plug " << replug);
    const auto unplugged = Clock::now();
    gadget.unplug();
    REQUIRE(wait_for([&] { return bridge.snapshot().failsafe; }));
    WARN("USB unplug -> failsafe: " << ms_since(unplugged) << " ms");
    CHECK(bridge.snapshot().failsafe_reason == "pad: disconnected");
    // A watcher of our own times libusb's part: the arrival callback.
    io::UsbHotplug watcher(0x1209, 0x0002);
    REQUIRE(watcher.available());
    const auto plugged = Clock::now();
    gadget.plug();
    REQUIRE(watcher.wait_for_arrival(20000));
    WARN("USB re-plug -> libusb arrival callback: " << ms_since(plugged) << " ms");
    REQUIRE(wait_for([&] { return bridge.snapshot().sources[0].connected; }));
    WARN("USB re-plug -> bridge reopened: " << ms_since(plugged) << " ms");
    // The next periodic enumeration is 60 s after the start.
    CHECK(ms_since(started) < 55000);
    REQUIRE(gadget.send({0x01, 0x80, 0x80, 0x00}));
    REQUIRE(wait_for([&] { return !bridge.snapshot().failsafe; }));
    snap = bridge.snapshot();
    CHECK(snap.sources[0].reconnects == replug);
    CHECK_FALSE(snap.controls[control("deadman")].pressed);
    // The LEDs again, written on reopen: the request still holds.
    REQUIRE(wait_for([&] {
      leds = gadget.read_output(50);
      return leds.size() == 2 && (leds[1] & 0x09) == 0x09;
    }));
  }
  bridge.stop();
  CHECK(udevd.stop() >= 0);
}
