#include "hil/io/evdev_signals.hpp"

#include <libevdev/libevdev.h>
#include <linux/input.h>

#include <algorithm>
#include <cctype>
#include <cmath>

namespace rise::hil::io {
namespace {
namespace fp = rise::firmware_protocol;
using Term = EvdevSignals::Term;

std::string lower(const char* text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string code_name(unsigned type, unsigned code) {
  if (const char* name = libevdev_event_code_get_name(type, code)) return lower(name);
  return (type == EV_ABS ? "abs_" : "key_") + std::to_string(code);
}

// Sticks and hats read -1..1; a 0..N trigger or pedal 0..1.
bool is_centred(unsigned code, const input_absinfo& info) {
  return info.minimum < 0 || code == ABS_X || code == ABS_Y || code == ABS_RX || code == ABS_RY ||
         (code >= ABS_HAT0X && code <= ABS_HAT3Y);
}

// SDL's -1 on a hat's Y is up, -1 on X left.
int hat_bits(const EvdevDevice& device, uint16_t hat) {
  const int x = device.value(EV_ABS, ABS_HAT0X + 2u * hat), y = device.value(EV_ABS, ABS_HAT0Y + 2u * hat);
  return (y < 0 ? 1 : 0) | (x > 0 ? 2 : 0) | (y > 0 ? 4 : 0) | (x < 0 ? 8 : 0);
}

// The part of the input's -1..1 an SDL input (aN, +aN, -aN, aN~) reads.
void input_range(const fp::SdlInput& in, Term& t) {
  t.in_low = in.half > 0 ? 0.0 : in.half < 0 ? 0.0 : -1.0;
  t.in_high = in.half > 0 ? 1.0 : in.half < 0 ? -1.0 : 1.0;
  if (in.invert) std::swap(t.in_low, t.in_high);
}

// What an SDL target reads: a trigger 0..1, a stick -1..1, +x 0..1, -x 0..-1.
void output_range(const fp::SdlBinding& b, Term& t) {
  const bool trigger = b.target == "lefttrigger" || b.target == "righttrigger";
  t.out_low = b.target_half != 0 || trigger ? 0.0 : -1.0;
  t.out_high = b.target_half < 0 ? -1.0 : 1.0;
}

}  // namespace

std::vector<uint16_t> sdl_button_codes(const HasEventCode& has) {
  std::vector<uint16_t> codes;
  for (unsigned c = BTN_JOYSTICK; c < KEY_MAX; ++c)
    if (has(EV_KEY, c)) codes.push_back(static_cast<uint16_t>(c));
  for (unsigned c = 0; c < BTN_JOYSTICK; ++c)
    if (has(EV_KEY, c)) codes.push_back(static_cast<uint16_t>(c));
  return codes;
}

std::vector<uint16_t> sdl_axis_codes(const HasEventCode& has) {
  std::vector<uint16_t> codes;
  for (unsigned c = 0; c < ABS_MAX; ++c)
    if ((c < ABS_HAT0X || c > ABS_HAT3Y) && has(EV_ABS, c)) codes.push_back(static_cast<uint16_t>(c));
  return codes;
}

std::vector<uint16_t> sdl_hats(const HasEventCode& has) {
  std::vector<uint16_t> hats;
  for (unsigned h = 0; h < 4; ++h)
    if (has(EV_ABS, ABS_HAT0X + 2 * h) || has(EV_ABS, ABS_HAT0Y + 2 * h)) hats.push_back(static_cast<uint16_t>(h));
  return hats;
}

double normalise_abs(int value, int minimum, int maximum, int flat) {
  const double centre = 0.5 * (static_cast<double>(minimum) + static_cast<double>(maximum));
  const double half = 0.5 * (static_cast<double>(maximum) - static_cast<double>(minimum));
  const double dead = std::clamp(static_cast<double>(flat), 0.0, half);
  if (half <= dead) return 0.0;
  const double d = static_cast<double>(value) - centre;
  if (std::abs(d) <= dead) return 0.0;
  return std::clamp(std::copysign((std::abs(d) - dead) / (half - dead), d), -1.0, 1.0);
}

void EvdevSignals::add(std::string name, bool axis, Term term) {
  for (Signal& s : signals_)
    if (s.name == name) {
      s.terms.push_back(term);
      return;
    }
  names_.push_back(name);
  signals_.push_back({std::move(name), axis, {term}});
}

EvdevSignals::EvdevSignals(const EvdevDevice& device) {
  for (unsigned c = 0; c < KEY_MAX; ++c)
    if (device.has(EV_KEY, c)) add(code_name(EV_KEY, c), false, Term{Term::Kind::Key, static_cast<uint16_t>(c)});
  for (unsigned c = 0; c < ABS_MAX; ++c) {
    const input_absinfo* info = device.has(EV_ABS, c) ? device.absinfo(c) : nullptr;
    if (!info) continue;
    Term t{Term::Kind::Abs, static_cast<uint16_t>(c), 0, info->minimum, info->maximum, info->flat};
    if (!is_centred(c, *info)) t.out_low = 0.0, t.out_high = 1.0;
    else t.out_low = -1.0, t.out_high = 1.0;
    add(code_name(EV_ABS, c), true, t);
  }
  const HasEventCode has = [&](unsigned type, unsigned code) { return device.has(type, code); };
  for (const uint16_t hat : sdl_hats(has))
    for (const auto& [suffix, mask] : {std::pair{"up", 1}, {"right", 2}, {"down", 4}, {"left", 8}})
      add("hat" + std::to_string(hat) + "_" + suffix, false, Term{Term::Kind::Hat, hat, mask});
}

std::vector<std::string> EvdevSignals::add_sdl(const EvdevDevice& device, const fp::SdlMapping& mapping) {
  const HasEventCode has = [&](unsigned type, unsigned code) { return device.has(type, code); };
  const auto buttons = sdl_button_codes(has), axes = sdl_axis_codes(has), hats = sdl_hats(has);
  std::vector<std::string> problems;
  for (const fp::SdlBinding& b : mapping.bindings) {
    const auto& in = b.input;
    const std::size_t index = static_cast<std::size_t>(in.index);
    const std::size_t count = in.kind == fp::SdlInput::Kind::Button ? buttons.size()
                              : in.kind == fp::SdlInput::Kind::Axis ? axes.size()
                                                                    : hats.size();
    if (index >= count) {
      problems.push_back("sdl." + b.target + ": the device has no " +
                         (in.kind == fp::SdlInput::Kind::Button ? "b" : in.kind == fp::SdlInput::Kind::Axis ? "a" : "h") +
                         std::to_string(in.index) + " (" + std::to_string(count) + " of that kind)");
      continue;
    }
    Term t;
    if (in.kind == fp::SdlInput::Kind::Button) t = Term{Term::Kind::Key, buttons[index]};
    else if (in.kind == fp::SdlInput::Kind::Hat) t = Term{Term::Kind::Hat, hats[index], in.hat_mask};
    else {
      const input_absinfo* info = device.absinfo(axes[index]);
      t = Term{Term::Kind::Abs, axes[index], 0, info->minimum, info->maximum, info->flat};
      input_range(in, t);
    }
    const bool axis = fp::is_sdl_axis(b.target);
    if (axis) output_range(b, t);
    add("sdl." + b.target, axis, t);
  }
  return problems;
}

double EvdevSignals::term_value(const EvdevDevice& device, const Term& t, bool axis) const {
  if (t.kind != Term::Kind::Abs) {
    const bool on = t.kind == Term::Kind::Key ? device.value(EV_KEY, t.code) != 0
                                              : (hat_bits(device, t.code) & t.hat_mask) == t.hat_mask;
    return axis ? (on ? t.out_high : t.out_low) : (on ? 1.0 : 0.0);
  }
  const double a = normalise_abs(device.value(EV_ABS, t.code), t.minimum, t.maximum, t.flat);
  const double along = (a - t.in_low) / (t.in_high - t.in_low);  // 0..1 over the part read
  if (along < 0.0 || along > 1.0) return 0.0;  // the other half: no say
  // SDL: an axis drives a button from half its range on (threshold midway).
  return axis ? t.out_low + along * (t.out_high - t.out_low) : (along >= 0.5 ? 1.0 : 0.0);
}

void EvdevSignals::read(const EvdevDevice& device, std::span<double> values) const {
  for (std::size_t i = 0; i < signals_.size() && i < values.size(); ++i) {
    const Signal& s = signals_[i];
    double v = 0.0;
    for (const Term& t : s.terms) {
      const double term = term_value(device, t, s.axis);
      v = s.axis ? v + term : std::max(v, term);
    }
    values[i] = s.axis ? std::clamp(v, -1.0, 1.0) : v;
  }
}

}  // namespace rise::hil::io
