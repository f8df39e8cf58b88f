// evdev:// URLs, SDL's numbering of a Linux device's inputs and the axis
// normalisation, without a device (the device itself: tests/vcan/evdev_vm_test).

#include <catch2/catch.hpp>

#include <linux/input.h>

#include <set>
#include <utility>

#include "hil/io/evdev_device.hpp"
#include "hil/io/evdev_signals.hpp"

namespace io = rise::hil::io;

TEST_CASE("evdev:// URL grammar", "[evdev]") {
  auto path = io::parse_evdev_url("evdev:///dev/input/event5");
  REQUIRE(path);
  CHECK(path->by == io::EvdevUrl::By::Path);
  CHECK(path->path == "/dev/input/event5");
  auto by_id = io::parse_evdev_url("evdev://by-id/usb-045e_028e-event-joystick");
  REQUIRE(by_id);
  CHECK(by_id->path == "/dev/input/by-id/usb-045e_028e-event-joystick");
  auto name = io::parse_evdev_url("evdev://name/Microsoft%20X-Box%20360%20pad");
  REQUIRE(name);
  CHECK(name->by == io::EvdevUrl::By::Name);
  CHECK(name->name == "Microsoft X-Box 360 pad");
  auto ids = io::parse_evdev_url("evdev://045e:028e");
  REQUIRE(ids);
  CHECK(ids->by == io::EvdevUrl::By::Ids);
  CHECK(ids->vendor_id == 0x045e);
  CHECK(ids->product_id == 0x028e);
  std::string error;
  for (const char* bad : {"evdev://", "evdev://045e:", "evdev://12345:1", "evdev://name/%2", "evdev://by-id/",
                          "evdev://pad", "hid://045e:028e"}) {
    INFO(bad);
    CHECK_FALSE(io::parse_evdev_url(bad, &error));
    CHECK(error.rfind(std::string("'") + bad + "': ", 0) == 0);
  }
  CHECK_THROWS_AS(io::EvdevDevice("evdev://pad"), std::invalid_argument);
}

TEST_CASE("SDL numbers an Xbox 360 pad's inputs as its database line expects", "[evdev]") {
  // The keys and axes xpad gives the pad (drivers/input/joystick/xpad.c).
  const std::set<std::pair<unsigned, unsigned>> codes = {
      {EV_KEY, BTN_A},     {EV_KEY, BTN_B},      {EV_KEY, BTN_X},     {EV_KEY, BTN_Y},
      {EV_KEY, BTN_TL},    {EV_KEY, BTN_TR},     {EV_KEY, BTN_SELECT}, {EV_KEY, BTN_START},
      {EV_KEY, BTN_MODE},  {EV_KEY, BTN_THUMBL}, {EV_KEY, BTN_THUMBR}, {EV_KEY, KEY_A},  // a key below BTN_JOYSTICK
      {EV_ABS, ABS_X},     {EV_ABS, ABS_Y},      {EV_ABS, ABS_Z},     {EV_ABS, ABS_RX},
      {EV_ABS, ABS_RY},    {EV_ABS, ABS_RZ},     {EV_ABS, ABS_HAT0X}, {EV_ABS, ABS_HAT0Y},
      {EV_ABS, ABS_HAT2Y}, {EV_ABS, ABS_MISC}};
  const io::HasEventCode has = [&](unsigned type, unsigned code) { return codes.count({type, code}) > 0; };
  // gamecontrollerdb.txt's 030000005e0400008e02000010010000: a:b0 b:b1 x:b2
  // y:b3 leftshoulder:b4 rightshoulder:b5 back:b6 start:b7 guide:b8
  // leftstick:b9 rightstick:b10; then keys under BTN_JOYSTICK.
  CHECK(io::sdl_button_codes(has) == std::vector<uint16_t>{BTN_A, BTN_B, BTN_X, BTN_Y, BTN_TL, BTN_TR, BTN_SELECT,
                                                           BTN_START, BTN_MODE, BTN_THUMBL, BTN_THUMBR, KEY_A});
  // leftx:a0 lefty:a1 lefttrigger:a2 rightx:a3 righty:a4 righttrigger:a5; hats skipped.
  CHECK(io::sdl_axis_codes(has) == std::vector<uint16_t>{ABS_X, ABS_Y, ABS_Z, ABS_RX, ABS_RY, ABS_RZ, ABS_MISC});
  CHECK(io::sdl_hats(has) == std::vector<uint16_t>{0, 2});
}

TEST_CASE("evdev axes: centred, flat as a dead zone, continuous", "[evdev]") {
  CHECK(io::normalise_abs(-32768, -32768, 32767, 0) == Approx(-1.0));
  CHECK(io::normalise_abs(32767, -32768, 32767, 0) == Approx(1.0));
  CHECK(io::normalise_abs(0, -32768, 32767, 128) == 0.0);
  CHECK(io::normalise_abs(127, -32768, 32767, 128) == 0.0);  // the centre is -0.5
  CHECK(io::normalise_abs(129, -32768, 32767, 128) == Approx((129 + 0.5 - 128) / (32767.5 - 128)));
  CHECK(io::normalise_abs(255, 0, 255, 0) == Approx(1.0));
  CHECK(io::normalise_abs(0, 0, 255, 0) == Approx(-1.0));
  CHECK(io::normalise_abs(-1, -1, 1, 0) == -1.0);
  CHECK(io::normalise_abs(5, 5, 5, 0) == 0.0);  // no range: no value
  CHECK(io::normalise_abs(70000, -32768, 32767, 0) == 1.0);
}
