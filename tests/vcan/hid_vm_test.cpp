// hid:// against the real kernel HID stack: a gamepad created through uhid
// (/dev/uhid, the kernel's user-space HID transport) is found by hidapi's
// hidraw enumeration, opened by HidDevice, decoded by the bridge, unplugged
// (UHID_DESTROY) and plugged in again. Runs only inside the VM of
// run_in_vcan_vm.sh (modules hid, uhid, hid-generic), as root.

#include <catch2/catch.hpp>

#include <fcntl.h>
#include <linux/uhid.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <functional>
#include <thread>

#include "firmware_protocol/hid_report.hpp"
#include "hil/bridge.hpp"
#include "hil/io/hid_device.hpp"
#include "panels/panel_definition.hpp"

namespace io = rise::io;
using rise::hil::Bridge;
using rise::hil::PanelSnapshot;

namespace {

// Gravis GamePad Pro USB (0428:4001), the descriptor of Android's CTS test
// gravis_gamepadprousb_register.json: x, y (8 bits each), buttons 1..10.
const uint8_t gravis_descriptor[] = {
    0x05, 0x01, 0x09, 0x05, 0xa1, 0x01, 0x05, 0x01, 0x09, 0x01, 0xa1, 0x00, 0x09, 0x30, 0x09, 0x31, 0x15,
    0x00, 0x26, 0xff, 0x00, 0x75, 0x08, 0x95, 0x02, 0x81, 0x02, 0xc0, 0x05, 0x09, 0x19, 0x01, 0x29, 0x0a,
    0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x0a, 0x81, 0x02, 0x95, 0x01, 0x75, 0x06, 0x81, 0x01, 0xc0};

// One virtual device on /dev/uhid: created in the constructor, destroyed
// (unplugged) by destroy() or the destructor.
class UhidGamepad {
 public:
  UhidGamepad() {
    fd_ = ::open("/dev/uhid", O_RDWR | O_CLOEXEC);
    REQUIRE(fd_ >= 0);
    uhid_event ev{};
    ev.type = UHID_CREATE2;
    std::strcpy(reinterpret_cast<char*>(ev.u.create2.name), "Gravis GamePad Pro (uhid)");
    std::strcpy(reinterpret_cast<char*>(ev.u.create2.uniq), "rise-uhid-1");
    ev.u.create2.rd_size = sizeof(gravis_descriptor);
    // Bluetooth, not USB: hidapi's hidraw backend looks for a USB parent
    // device for BUS_USB, and a uhid device has none.
    ev.u.create2.bus = 0x05;  // BUS_BLUETOOTH
    ev.u.create2.vendor = 0x0428;
    ev.u.create2.product = 0x4001;
    std::memcpy(ev.u.create2.rd_data, gravis_descriptor, sizeof(gravis_descriptor));
    REQUIRE(::write(fd_, &ev, sizeof(ev)) == static_cast<ssize_t>(sizeof(ev)));
  }
  ~UhidGamepad() { destroy(); }
  UhidGamepad(const UhidGamepad&) = delete;
  UhidGamepad& operator=(const UhidGamepad&) = delete;

  void send(std::initializer_list<uint8_t> report) {
    uhid_event ev{};
    ev.type = UHID_INPUT2;
    ev.u.input2.size = static_cast<uint16_t>(report.size());
    std::copy(report.begin(), report.end(), ev.u.input2.data);
    REQUIRE(::write(fd_, &ev, sizeof(ev)) == static_cast<ssize_t>(sizeof(ev)));
  }
  void destroy() {
    if (fd_ < 0) return;
    uhid_event ev{};
    ev.type = UHID_DESTROY;
    (void)::write(fd_, &ev, sizeof(ev));
    ::close(fd_);
    fd_ = -1;
  }

 private:
  int fd_ = -1;
};

// Polls `done` until it holds or `timeout` passes (the VM runs under TCG:
// generous deadlines, never fixed sleeps).
bool wait_for(const std::function<bool()>& done, std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return done();
}

const char* definition_text =
    "panel: gravis\n"
    "sources:\n"
    "  - {name: pad, protocol: hid, device: 'hid://0428:4001', timeout_ms: 0}\n"
    "controls:\n"
    "  - {name: stick_x, kind: axis, signal: x, safe: 0}\n"
    "  - {name: stick_y, kind: axis, signal: y, safe: 0}\n"
    "  - {name: red, kind: button, signal: button_1, safe: false}\n"
    "  - {name: green, kind: button, signal: button_3, safe: false}\n"
    "  - {name: start, kind: button, signal: button_10, safe: false}\n";

}  // namespace

TEST_CASE("HidDevice finds a uhid gamepad by VID:PID and reads its descriptor and reports", "[vcan]") {
  UhidGamepad pad;
  io::HidDevice device("hid://0428:4001?name=GamePad");
  REQUIRE(wait_for([&] { return device.reopen() == io::IoStatus::Ok; }));
  CHECK(device.path().rfind("/dev/hidraw", 0) == 0);
  CHECK(device.report_descriptor() ==
        std::vector<uint8_t>(std::begin(gravis_descriptor), std::end(gravis_descriptor)));
  SECTION("a report sent by the device is read as sent") {
    pad.send({0x00, 0xff, 0x05, 0x02});
    std::array<uint8_t, 64> report{};
    std::size_t length = 0;
    REQUIRE(device.read(report, length, 5000) == io::IoStatus::Ok);
    CHECK(std::vector<uint8_t>(report.begin(), report.begin() + static_cast<std::ptrdiff_t>(length)) ==
          std::vector<uint8_t>{0x00, 0xff, 0x05, 0x02});
  }
  SECTION("unplugging reads as Disconnected") {
    pad.destroy();
    std::array<uint8_t, 64> report{};
    std::size_t length = 0;
    io::IoStatus st = io::IoStatus::Timeout;
    REQUIRE(wait_for([&] { return (st = device.read(report, length, 10)) != io::IoStatus::Timeout; }));
    CHECK(st == io::IoStatus::Disconnected);
    CHECK_FALSE(device.is_open());
    CHECK(device.reopen() == io::IoStatus::Disconnected);
  }
  SECTION("another VID:PID is not matched") {
    io::HidDevice other("hid://0428:4002");
    CHECK(other.reopen() == io::IoStatus::Disconnected);
    io::HidDevice other_serial("hid://0428:4001?serial=nope");
    CHECK(other_serial.reopen() == io::IoStatus::Disconnected);
  }
}

TEST_CASE("bridge decodes a uhid gamepad, goes failsafe when it is unplugged and reopens it", "[vcan]") {
  auto pad = std::make_unique<UhidGamepad>();
  std::vector<rise::hil::SourceTransport> transports(1);
  transports[0].hid = std::make_unique<io::HidDevice>("hid://0428:4001");
  rise::hil::BridgeSettings settings;
  Bridge bridge(rise::panels::parse_panel_definition(definition_text, "gravis.yaml"), std::move(transports),
                [](const PanelSnapshot&) {}, settings);
  bridge.start();
  const auto control = [&](const char* name) { return *bridge.definition().find_control(name); };

  REQUIRE(wait_for([&] { return bridge.snapshot().sources[0].connected; }));
  CHECK(bridge.snapshot().failsafe_reason == "pad: no report yet");
  // Worked example of hid_report.hpp: x -1, y +1, buttons 1, 3 and 10.
  pad->send({0x00, 0xff, 0x05, 0x02});
  REQUIRE(wait_for([&] { return !bridge.snapshot().failsafe; }));
  PanelSnapshot snap = bridge.snapshot();
  CHECK(snap.controls[control("stick_x")].axis == Approx(-1.0).margin(1e-6));
  CHECK(snap.controls[control("stick_y")].axis == Approx(1.0).margin(1e-6));
  CHECK(snap.controls[control("red")].pressed);
  CHECK(snap.controls[control("green")].pressed);
  CHECK(snap.controls[control("start")].pressed);

  pad->send({0xff, 0x00, 0x00, 0x00});
  REQUIRE(wait_for([&] { return !bridge.snapshot().controls[control("red")].pressed; }));
  snap = bridge.snapshot();
  CHECK(snap.controls[control("stick_x")].axis == Approx(1.0).margin(1e-6));
  CHECK(snap.controls[control("stick_y")].axis == Approx(-1.0).margin(1e-6));
  CHECK_FALSE(snap.controls[control("start")].pressed);

  // Unplug: failsafe within a publish period (10 ms at 100 Hz) of the kernel
  // removing the node; measured here including the guest's scheduling.
  pad->send({0x7f, 0x7f, 0x04, 0x00});
  REQUIRE(wait_for([&] { return bridge.snapshot().controls[control("green")].pressed; }));
  const auto unplugged = std::chrono::steady_clock::now();
  pad.reset();
  REQUIRE(wait_for([&] { return bridge.snapshot().failsafe; }));
  const auto failsafe_ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - unplugged).count();
  WARN("unplug -> failsafe: " << failsafe_ms << " ms");
  snap = bridge.snapshot();
  CHECK_FALSE(snap.sources[0].connected);
  CHECK(snap.failsafe_reason == "pad: disconnected");
  CHECK(snap.controls[control("green")].forced_safe);
  CHECK_FALSE(snap.controls[control("green")].pressed);

  // Plug in again: found by the next enumeration (every 500 ms).
  const auto plugged = std::chrono::steady_clock::now();
  pad = std::make_unique<UhidGamepad>();
  REQUIRE(wait_for([&] { return bridge.snapshot().sources[0].connected; }));
  const auto reopen_ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - plugged).count();
  WARN("plug -> reopened: " << reopen_ms << " ms");
  pad->send({0x7f, 0x7f, 0x00, 0x02});
  REQUIRE(wait_for([&] { return !bridge.snapshot().failsafe; }));
  snap = bridge.snapshot();
  CHECK(snap.controls[control("start")].pressed);
  CHECK(snap.controls[control("stick_x")].axis == Approx(0.0).margin(0.01));
  CHECK(snap.sources[0].reconnects == 1);
  bridge.stop();
}
