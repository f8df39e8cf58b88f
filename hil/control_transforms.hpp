#pragma once

// Per-control transforms between a source's raw signal and the named
// control: axis shaping (deadband, expo, scale, invert), a first-order
// low-pass, button filters (debounce, toggle, long press, edge pulse) and
// multi-position switches read from several bits. Pure and allocation-free:
// safe in the cyclic path. Times are monotonic microseconds.

#include <cstdint>
#include <optional>
#include <span>

namespace rise::hil {

struct AxisShaping {
  float deadband = 0.0f;  ///< |x| ≤ deadband → 0; the remaining travel is rescaled to stay continuous
  float expo = 0.0f;      ///< 0 linear .. 1 cubic: y = (1 − e)·x + e·x³ (the RC transmitters' expo)
  float scale = 1.0f;     ///< applied last, 0..1
  bool invert = false;    ///< applied first
};

/// Deadband → expo → scale, after the optional inversion; result in -1..1.
float shape_axis(float raw, const AxisShaping& shaping);

/// First-order low-pass y' = (x − y)/τ, exact for piecewise-constant input:
/// y += (x − y)·(1 − e^(−Δt/τ)). τ = 0 passes the input through.
class LowPass {
 public:
  explicit LowPass(float tau_ms = 0.0f) : tau_us_(tau_ms * 1000.0f) {}
  float update(float x, int64_t now_us);
  /// Jumps to x (e.g. to the safe value when the source is lost).
  void reset(float x, int64_t now_us);

 private:
  float tau_us_;
  float y_ = 0.0f;
  int64_t last_us_ = -1;
};

enum class ButtonMode {
  Direct,     ///< output = debounced input
  Toggle,     ///< each press flips the output (a latching function on a momentary button)
  LongPress,  ///< output true while held, once held for long_press_ms
  Edge,       ///< output true for pulse_ms after each press
};

struct ButtonSettings {
  ButtonMode mode = ButtonMode::Direct;
  uint32_t debounce_ms = 0;  ///< a change counts once it has held this long
  uint32_t long_press_ms = 800;
  uint32_t pulse_ms = 100;
};

class ButtonFilter {
 public:
  explicit ButtonFilter(ButtonSettings settings = {}) : s_(settings) {}
  /// Feeds the raw state at now_us; returns the filtered output.
  bool update(bool raw, int64_t now_us);
  /// Forgets history: output `output`, debounced input `raw` (used when the
  /// source comes back, so a held button does not toggle or pulse).
  void reset(bool raw, bool output, int64_t now_us);
  bool output() const { return output_; }

 private:
  ButtonSettings s_;
  bool stable_ = false;     // debounced input
  bool candidate_ = false;  // raw value waiting to be accepted
  int64_t candidate_since_us_ = 0;
  int64_t pressed_since_us_ = 0;
  int64_t pulse_until_us_ = 0;
  bool output_ = false;
  bool started_ = false;
};

enum class BitsEncoding {
  Binary,  ///< position = the bits read as a binary number (first bit = LSB)
  OneHot,  ///< position = index of the one set bit; none or several set → invalid
};

/// Position of a multi-position switch wired to several inputs (e.g. a
/// 3-position rotary switch on two digital inputs). nullopt when the bits do
/// not form a valid position (one-hot with zero or several set, or a binary
/// value ≥ positions).
std::optional<uint8_t> switch_from_bits(uint32_t bits, std::span<const uint8_t> bit_indices,
                                        BitsEncoding encoding, std::size_t positions);

}  // namespace rise::hil
