// evdev:// against the real kernel input stack: a uinput device
// (/dev/uinput: UI_DEV_SETUP, UI_ABS_SETUP) with the Xbox 360 pad's ids
// (045e:028e, version 0x0110, bus USB) and the keys and axes xpad gives it
// stands in for the pad. The bridge reads it with `mapping: sdl` from
// SDL_GameControllerDB's real gamecontrollerdb.txt: axes and buttons arrive
// under SDL's names with their values, unplugging (UI_DEV_DESTROY) puts the
// controls at their safe values, creating it again reopens it (seen through
// inotify on /dev/input), and the panel's rumble reaches the device as an
// FF_RUMBLE upload and play. Runs only inside the VM of run_in_vcan_vm.sh
// (modules evdev, uinput), as root.

#include <catch2/catch.hpp>

#include <fcntl.h>
#include <linux/uinput.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <thread>

#include "hil/bridge.hpp"
#include "hil/io/evdev_device.hpp"
#include "hil/source_factory.hpp"
#include "panels/panel_definition.hpp"

namespace io = rise::hil::io;
using rise::hil::Bridge;
using rise::hil::PanelSnapshot;

namespace {

constexpr const char* kPadName = "Microsoft X-Box 360 pad";

bool wait_for(const std::function<bool()>& done, std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return done();
}

int64_t ms_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - t).count();
}

// A uinput Xbox 360 pad as xpad (drivers/input/joystick/xpad.c) presents it.
class UinputPad {
 public:
  UinputPad() {
    fd_ = ::open("/dev/uinput", O_RDWR | O_NONBLOCK | O_CLOEXEC);
    REQUIRE(fd_ >= 0);
    set(UI_SET_EVBIT, EV_KEY);
    for (const int key : {BTN_A, BTN_B, BTN_X, BTN_Y, BTN_TL, BTN_TR, BTN_SELECT, BTN_START, BTN_MODE, BTN_THUMBL,
                          BTN_THUMBR})
      set(UI_SET_KEYBIT, key);
    set(UI_SET_EVBIT, EV_ABS);
    for (const int stick : {ABS_X, ABS_Y, ABS_RX, ABS_RY}) axis(stick, -32768, 32767, 16, 128);
    for (const int trigger : {ABS_Z, ABS_RZ}) axis(trigger, 0, 255, 0, 0);
    for (const int hat : {ABS_HAT0X, ABS_HAT0Y}) axis(hat, -1, 1, 0, 0);
    set(UI_SET_EVBIT, EV_FF);
    set(UI_SET_FFBIT, FF_RUMBLE);
    uinput_setup setup{};
    setup.id = {BUS_USB, 0x045e, 0x028e, 0x0110};
    std::snprintf(setup.name, sizeof setup.name, "%s", kPadName);
    setup.ff_effects_max = 1;
    REQUIRE(::ioctl(fd_, UI_DEV_SETUP, &setup) == 0);
    REQUIRE(::ioctl(fd_, UI_DEV_CREATE) == 0);
  }
  ~UinputPad() {
    ::ioctl(fd_, UI_DEV_DESTROY);
    ::close(fd_);
  }
  UinputPad(const UinputPad&) = delete;
  UinputPad& operator=(const UinputPad&) = delete;

  void emit(int type, int code, int value) {
    input_event ev{};
    ev.type = static_cast<uint16_t>(type);
    ev.code = static_cast<uint16_t>(code);
    ev.value = value;
    REQUIRE(::write(fd_, &ev, sizeof ev) == static_cast<ssize_t>(sizeof ev));
  }
  void frame(std::initializer_list<std::tuple<int, int, int>> events) {
    for (const auto& [type, code, value] : events) emit(type, code, value);
    emit(EV_SYN, SYN_REPORT, 0);
  }
  // Serves one FF upload request (the host's EVIOCSFF waits for it) and
  // returns its strong magnitude once the host plays the effect.
  std::optional<int> serve_rumble(std::chrono::milliseconds timeout) {
    std::optional<int> strong;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 10) <= 0) continue;
      input_event ev{};
      if (::read(fd_, &ev, sizeof ev) != static_cast<ssize_t>(sizeof ev)) continue;
      if (ev.type == EV_UINPUT && ev.code == UI_FF_UPLOAD) strong = upload(static_cast<uint32_t>(ev.value));
      if (ev.type == EV_FF && ev.value == 1 && strong) return strong;
    }
    return std::nullopt;
  }

 private:
  void set(unsigned long request, int value) { REQUIRE(::ioctl(fd_, request, value) == 0); }
  void axis(int code, int minimum, int maximum, int fuzz, int flat) {
    set(UI_SET_ABSBIT, code);
    uinput_abs_setup abs{};
    abs.code = static_cast<uint16_t>(code);
    abs.absinfo.minimum = minimum;
    abs.absinfo.maximum = maximum;
    abs.absinfo.fuzz = fuzz;
    abs.absinfo.flat = flat;
    REQUIRE(::ioctl(fd_, UI_ABS_SETUP, &abs) == 0);
  }
  int upload(uint32_t request_id) {
    uinput_ff_upload up{};
    up.request_id = request_id;
    REQUIRE(::ioctl(fd_, UI_BEGIN_FF_UPLOAD, &up) == 0);
    CHECK(up.effect.type == FF_RUMBLE);
    up.retval = 0;
    REQUIRE(::ioctl(fd_, UI_END_FF_UPLOAD, &up) == 0);
    return up.effect.u.rumble.strong_magnitude;
  }
  int fd_ = -1;
};

std::string sdl_db() { return RISE_SDL_DB; }

std::string definition_text() {
  return "panel: xbox\n"
         "sources:\n"
         "  - {name: pad, protocol: hid, device: 'evdev://045e:028e', mapping: sdl, sdl_db: '" + sdl_db() + "'}\n"
         "controls:\n"
         "  - {name: steer, kind: axis, signal: sdl.leftx, safe: 0}\n"
         "  - {name: brake, kind: axis, signal: sdl.lefttrigger, safe: 0}\n"
         "  - {name: look, kind: axis, signal: abs_ry, safe: 0}\n"
         "  - {name: horn, kind: button, signal: sdl.a, safe: false}\n"
         "  - {name: up, kind: button, signal: sdl.dpup, safe: false}\n"
         "  - {name: menu, kind: button, signal: sdl.start, safe: false}\n"
         "feedback:\n"
         "  rumble:\n"
         "    - {name: shaker, source: pad, signal: ff_rumble}\n";
}

}  // namespace

TEST_CASE("EvdevDevice finds the uinput pad by name, VID:PID, node and link", "[vcan]") {
  UinputPad pad;
  io::EvdevDevice by_name("evdev://name/Microsoft%20X-Box%20360%20pad");
  REQUIRE(wait_for([&] { return by_name.reopen() == io::IoStatus::Ok; }));
  CHECK(by_name.identity().name == kPadName);
  CHECK(by_name.identity().bus == BUS_USB);
  CHECK(by_name.identity().vendor_id == 0x045e);
  CHECK(by_name.identity().product_id == 0x028e);
  CHECK(by_name.identity().version == 0x0110);
  io::EvdevDevice by_ids("evdev://045e:028e");
  REQUIRE(by_ids.reopen() == io::IoStatus::Ok);
  CHECK(by_ids.path() == by_name.path());
  io::EvdevDevice by_node("evdev://" + by_name.path());
  REQUIRE(by_node.reopen() == io::IoStatus::Ok);
  // udev makes /dev/input/by-id links; the VM has no udev: made here as it would.
  std::filesystem::create_directories("/dev/input/by-id");
  std::filesystem::create_symlink(by_name.path(), "/dev/input/by-id/usb-Microsoft_X-Box_360_pad-event-joystick");
  io::EvdevDevice by_id("evdev://by-id/usb-Microsoft_X-Box_360_pad-event-joystick");
  REQUIRE(by_id.reopen() == io::IoStatus::Ok);
  CHECK(by_id.path() == by_name.path());
  std::filesystem::remove("/dev/input/by-id/usb-Microsoft_X-Box_360_pad-event-joystick");
  io::EvdevDevice absent("evdev://dead:beef");
  CHECK(absent.reopen() == io::IoStatus::Disconnected);
  CHECK(absent.last_error() == "evdev://dead:beef: no such input device");
}

TEST_CASE("bridge reads the uinput pad under SDL's names, goes safe when unplugged, reopens it", "[vcan]") {
  if (!std::filesystem::exists(sdl_db())) {
    WARN("skipped: " << sdl_db() << " not found (RISE_TEST_DATA)");
    return;
  }
  auto pad = std::make_unique<UinputPad>();
  const auto definition = rise::panels::parse_panel_definition(definition_text(), "xbox.yaml");
  std::vector<std::unique_ptr<rise::hil::SourceTransport>> transports;
  transports.push_back(rise::hil::open_source(definition, 0, "-"));
  rise::hil::BridgeSettings settings;
  settings.hid_enumerate_ms = 5000;  // a quick reopen can only come from inotify
  Bridge bridge(definition, std::move(transports), [](const PanelSnapshot&) {}, settings);
  bridge.start();
  const auto value = [&](const char* name) { return bridge.snapshot().controls[*definition.find_control(name)]; };

  REQUIRE(wait_for([&] { return !bridge.snapshot().failsafe; }));
  CHECK(value("steer").axis == Approx(0.0).margin(1e-9));
  pad->frame({{EV_ABS, ABS_X, 32767}, {EV_ABS, ABS_Z, 255}, {EV_KEY, BTN_A, 1}, {EV_ABS, ABS_HAT0Y, -1},
              {EV_ABS, ABS_RY, -32768}});
  REQUIRE(wait_for([&] { return value("horn").pressed; }));
  CHECK(value("steer").axis == Approx(1.0).margin(1e-6));
  CHECK(value("brake").axis == Approx(1.0).margin(1e-6));
  CHECK(value("look").axis == Approx(-1.0).margin(1e-6));
  CHECK(value("up").pressed);
  CHECK_FALSE(value("menu").pressed);

  // Within flat (128) of the centre: 0; beyond: rescaled from the flat's edge.
  pad->frame({{EV_ABS, ABS_X, 100}, {EV_ABS, ABS_Z, 0}, {EV_KEY, BTN_A, 0}, {EV_ABS, ABS_HAT0Y, 0},
              {EV_KEY, BTN_START, 1}});
  REQUIRE(wait_for([&] { return value("menu").pressed; }));
  CHECK(value("steer").axis == Approx(0.0).margin(1e-9));
  CHECK(value("brake").axis == Approx(0.0).margin(1e-6));
  CHECK_FALSE(value("horn").pressed);
  CHECK_FALSE(value("up").pressed);
  pad->frame({{EV_ABS, ABS_X, -16384}});
  REQUIRE(wait_for([&] { return value("steer").axis < -0.1f; }));
  CHECK(value("steer").axis == Approx(-(16384.0 - 0.5 - 128.0) / (32767.5 - 128.0)).margin(1e-5));

  // The rumble: an FF_RUMBLE upload the device serves, then played.
  rise::hil::FeedbackRequest request;
  request.rumble = 0.5f;
  bridge.set_feedback(request);
  const auto strong = pad->serve_rumble(std::chrono::seconds(10));
  REQUIRE(strong);
  CHECK(*strong == 32768);
  request.rumble = 0.0f;  // stopped: no upload, so the unplugged pad leaves no request waiting
  bridge.set_feedback(request);
  CHECK(bridge.snapshot().sources[0].reconnects == 0);

  // Unplug with a button held: safe values, published at once.
  pad->frame({{EV_KEY, BTN_A, 1}});
  REQUIRE(wait_for([&] { return value("horn").pressed; }));
  const auto unplugged = std::chrono::steady_clock::now();
  pad.reset();
  REQUIRE(wait_for([&] { return bridge.snapshot().failsafe; }));
  const int64_t failsafe_ms = ms_since(unplugged);
  WARN("unplug -> failsafe: " << failsafe_ms << " ms (publish period 10 ms)");
  CHECK(failsafe_ms <= 10 * 5);  // TCG guest: a publish period, with its scheduling
  PanelSnapshot snap = bridge.snapshot();
  CHECK(snap.failsafe_reason == "pad: disconnected");
  CHECK(snap.controls[*definition.find_control("horn")].forced_safe);
  CHECK_FALSE(snap.controls[*definition.find_control("horn")].pressed);
  CHECK(snap.controls[*definition.find_control("steer")].axis == 0.0f);

  // Created again: reopened when its node appears (inotify), long before
  // the 5 s enumeration.
  const auto plugged = std::chrono::steady_clock::now();
  pad = std::make_unique<UinputPad>();
  REQUIRE(wait_for([&] { return bridge.snapshot().sources[0].connected; }));
  const int64_t reopen_ms = ms_since(plugged);

  WARN("plug -> reopened: " << reopen_ms << " ms");
  CHECK(reopen_ms < 2000);
  pad->frame({{EV_KEY, BTN_A, 1}, {EV_ABS, ABS_X, -32768}});
  REQUIRE(wait_for([&] { return value("horn").pressed; }));
  CHECK(value("steer").axis == Approx(-1.0).margin(1e-6));
  CHECK_FALSE(bridge.snapshot().failsafe);
  CHECK(bridge.snapshot().sources[0].reconnects == 1);
  bridge.stop();
}
