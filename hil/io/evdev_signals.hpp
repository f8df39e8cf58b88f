#pragma once

// The named signals of an evdev device (evdev_device.hpp), as a panel's
// controls bind them:
//
//   - the kernel's names of its codes, lowercase (libevdev's names):
//     abs_x, abs_rz, abs_hat0x, btn_south, btn_tl, key_volumeup... Keys
//     read 0 / 1; sticks (abs_x, abs_y, abs_rx, abs_ry, the hats and any
//     axis whose range goes below 0) -1..1 from their range, other axes
//     (triggers: abs_z, abs_rz, abs_gas, abs_brake... of 0..N) 0..1;
//   - a hat's directions as buttons: hat0_up, hat0_down, hat0_left, hat0_right;
//   - with an SDL mapping (firmware_protocol/sdl_mapping.hpp): sdl.<name>
//     for each element of the device's line (sdl.leftx, sdl.a, sdl.dpup...),
//     SDL's buttons 0 / 1, its sticks -1..1, its triggers 0..1.
//
// An axis is centred at (min + max) / 2 and its flat (absinfo.flat) is a
// dead zone around the centre, the rest rescaled so the value stays
// continuous; the kernel itself drops changes within fuzz
// (input_handle_abs_event), so fuzz needs nothing here.
//
// SDL's numbering of a Linux device's inputs (bN, aN, hN), as SDL2's joystick
// driver counts them in ConfigJoystick() (src/joystick/linux/SDL_sysjoystick.c,
// SDL 2.0.x..2.30): buttons are the keys the device has from BTN_JOYSTICK up
// to KEY_MAX, then those from 0 up to BTN_JOYSTICK; axes the absolute axes
// from 0 up to ABS_MAX, skipping ABS_HAT0X..ABS_HAT3Y; hats the pairs
// ABS_HAT0X/Y..ABS_HAT3X/Y of which the device has either axis. SDL maps a
// hat's -1 on Y to up and on X to left.

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "firmware_protocol/sdl_mapping.hpp"
#include "hil/io/evdev_device.hpp"

namespace rise::hil::io {

/// Whether the device has event code `code` of type `type` (EV_KEY, EV_ABS).
using HasEventCode = std::function<bool(unsigned type, unsigned code)>;

/// SDL's bN, aN and hN of a device: the event codes in SDL's order (hats:
/// the number of each hat, 0..3).
std::vector<uint16_t> sdl_button_codes(const HasEventCode& has);
std::vector<uint16_t> sdl_axis_codes(const HasEventCode& has);
std::vector<uint16_t> sdl_hats(const HasEventCode& has);

/// -1..1 of an axis value: centred, flat as a dead zone. Cyclic-path safe.
double normalise_abs(int value, int minimum, int maximum, int flat);

class EvdevSignals {
 public:
  /// Every code of the open `device` under its kernel name.
  explicit EvdevSignals(const EvdevDevice& device);

  /// Adds sdl.<target> for each element of `mapping`; an element naming
  /// an input the device lacks is left out and said in the returned lines.
  std::vector<std::string> add_sdl(const EvdevDevice& device, const firmware_protocol::SdlMapping& mapping);

  const std::vector<std::string>& names() const { return names_; }
  /// The signals' values (indexed like names()) from the device's state.
  /// No allocation, no throw.
  void read(const EvdevDevice& device, std::span<double> values) const;

  /// One input feeding a signal, and how it maps onto the signal's range.
  struct Term {
    enum class Kind : uint8_t { Key, Abs, Hat } kind = Kind::Key;
    uint16_t code = 0;   ///< key or axis; hats: the hat's number
    int hat_mask = 0;    ///< hats: SDL's 1 up, 2 right, 4 down, 8 left
    int minimum = 0, maximum = 0, flat = 0;  ///< Abs: the axis's range
    double in_low = -1.0, in_high = 1.0;     ///< Abs: the part of -1..1 that drives the signal
    double out_low = 0.0, out_high = 1.0;    ///< what the signal reads at in_low / in_high (keys: released / pressed)
  };

 private:
  struct Signal {
    std::string name;
    bool axis = false;  ///< an axis sums its terms (clamped to -1..1); a button takes the largest
    std::vector<Term> terms;
  };
  void add(std::string name, bool axis, Term term);
  double term_value(const EvdevDevice& device, const Term& term, bool axis) const;

  std::vector<std::string> names_;
  std::vector<Signal> signals_;
};

}  // namespace rise::hil::io
