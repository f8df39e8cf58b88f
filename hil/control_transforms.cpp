#include "hil/control_transforms.hpp"

#include <algorithm>
#include <cmath>

namespace rise::hil {

float shape_axis(float raw, const AxisShaping& s) {
  float x = std::clamp(s.invert ? -raw : raw, -1.0f, 1.0f);
  const float magnitude = std::fabs(x);
  if (magnitude <= s.deadband) return 0.0f;
  x = std::copysign((magnitude - s.deadband) / (1.0f - s.deadband), x);
  x = (1.0f - s.expo) * x + s.expo * x * x * x;
  return std::clamp(s.scale * x, -1.0f, 1.0f);
}

float LowPass::update(float x, int64_t now_us) {
  if (tau_us_ <= 0.0f || last_us_ < 0) {
    y_ = x;
  } else {
    const float dt = static_cast<float>(std::max<int64_t>(0, now_us - last_us_));
    y_ += (x - y_) * (1.0f - std::exp(-dt / tau_us_));
  }
  last_us_ = now_us;
  return y_;
}

void LowPass::reset(float x, int64_t now_us) {
  y_ = x;
  last_us_ = now_us;
}

void ButtonFilter::reset(bool raw, bool output, int64_t now_us) {
  stable_ = candidate_ = raw;
  candidate_since_us_ = pressed_since_us_ = now_us;
  pulse_until_us_ = 0;
  output_ = output;
  started_ = true;
}

bool ButtonFilter::update(bool raw, int64_t now_us) {
  if (!started_) {
    // The first reading is the button's state, not a press: a button held at
    // start-up neither toggles nor pulses.
    reset(raw, s_.mode == ButtonMode::Direct ? raw : false, now_us);
    if (s_.mode != ButtonMode::LongPress) return output_;
  }
  if (raw != candidate_) {
    candidate_ = raw;
    candidate_since_us_ = now_us;
  }
  bool pressed_edge = false;
  if (candidate_ != stable_ && now_us - candidate_since_us_ >= int64_t{s_.debounce_ms} * 1000) {
    stable_ = candidate_;
    if (stable_) {
      pressed_edge = true;
      pressed_since_us_ = candidate_since_us_;
    }
  }
  switch (s_.mode) {
    case ButtonMode::Direct: output_ = stable_; break;
    case ButtonMode::Toggle:
      if (pressed_edge) output_ = !output_;
      break;
    case ButtonMode::LongPress:
      output_ = stable_ && now_us - pressed_since_us_ >= int64_t{s_.long_press_ms} * 1000;
      break;
    case ButtonMode::Edge:
      if (pressed_edge) pulse_until_us_ = now_us + int64_t{s_.pulse_ms} * 1000;
      output_ = now_us < pulse_until_us_;
      break;
  }
  return output_;
}

std::optional<uint8_t> switch_from_bits(uint32_t bits, std::span<const uint8_t> bit_indices,
                                        BitsEncoding encoding, std::size_t positions) {
  uint32_t value = 0;
  int set = 0;
  int index_of_set = -1;
  for (std::size_t i = 0; i < bit_indices.size(); ++i) {
    const bool on = (bits >> bit_indices[i]) & 1u;
    if (!on) continue;
    value |= 1u << i;
    ++set;
    index_of_set = static_cast<int>(i);
  }
  if (encoding == BitsEncoding::OneHot) {
    if (set != 1 || static_cast<std::size_t>(index_of_set) >= positions) return std::nullopt;
    return static_cast<uint8_t>(index_of_set);
  }
  if (value >= positions) return std::nullopt;
  return static_cast<uint8_t>(value);
}

}  // namespace rise::hil
