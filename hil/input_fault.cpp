#include "hil/input_fault.hpp"

#include "hil/io/seeded_draw.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace rise::hil {
namespace {


bool intermittently_lost(const InputFault& f, int64_t now_us) {
  const double slot_s = f.rate > 0.0 ? f.rate : 0.1;
  const double p = f.value > 0.0 ? f.value : 0.5;
  const auto slot = static_cast<uint64_t>(static_cast<double>(now_us - f.start_us) / (slot_s * 1e6));
  return seeded_uniform(f.seed, slot) < p;
}

float clamp_unit(double v) { return static_cast<float>(std::clamp(v, -1.0, 1.0)); }

}  // namespace

const char* to_string(InputFaultKind kind) {
  switch (kind) {
    case InputFaultKind::StuckAt: return "stuck_at";
    case InputFaultKind::Offset: return "offset";
    case InputFaultKind::Drift: return "drift";
    case InputFaultKind::Noise: return "noise";
    case InputFaultKind::OutOfRange: return "out_of_range";
    case InputFaultKind::Intermittent: return "intermittent";
    case InputFaultKind::Disconnect: return "disconnect";
  }
  return "?";
}

std::optional<InputFaultKind> parse_input_fault_kind(std::string_view name) {
  for (auto k : {InputFaultKind::StuckAt, InputFaultKind::Offset, InputFaultKind::Drift, InputFaultKind::Noise,
                 InputFaultKind::OutOfRange, InputFaultKind::Intermittent, InputFaultKind::Disconnect})
    if (name == to_string(k)) return k;
  return std::nullopt;
}

double seeded_uniform(uint64_t seed, uint64_t index) { return io::seeded_uniform(seed, index); }

double seeded_normal(uint64_t seed, uint64_t index) {
  const double u1 = 1.0 - seeded_uniform(seed, 2 * index);  // (0, 1]
  const double u2 = seeded_uniform(seed, 2 * index + 1);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

FaultEffect apply_axis_faults(std::span<const InputFault> faults, std::size_t control, int64_t now_us, float& unit) {
  FaultEffect effect = FaultEffect::None;
  for (const InputFault& f : faults) {
    if (f.control != control || !f.active(now_us)) continue;
    const double t_s = static_cast<double>(now_us - f.start_us) * 1e-6;
    switch (f.kind) {
      case InputFaultKind::StuckAt: unit = clamp_unit(f.value); break;
      case InputFaultKind::Offset: unit = clamp_unit(unit + f.value); break;
      case InputFaultKind::Drift: unit = clamp_unit(unit + f.rate * t_s); break;
      case InputFaultKind::Noise:
        unit = clamp_unit(unit + f.value * seeded_normal(f.seed, static_cast<uint64_t>((now_us - f.start_us) / 1000)));
        break;
      case InputFaultKind::OutOfRange:
        unit = static_cast<float>(std::abs(f.value) > 1.0 ? f.value : 1.5);
        return FaultEffect::OutOfRange;
      case InputFaultKind::Intermittent:
        if (intermittently_lost(f, now_us)) return FaultEffect::Lost;
        break;
      case InputFaultKind::Disconnect: return FaultEffect::Lost;
    }
    effect = FaultEffect::Changed;
  }
  return effect;
}

FaultEffect apply_button_faults(std::span<const InputFault> faults, std::size_t control, int64_t now_us,
                                bool& pressed) {
  FaultEffect effect = FaultEffect::None;
  for (const InputFault& f : faults) {
    if (f.control != control || !f.active(now_us)) continue;
    switch (f.kind) {
      case InputFaultKind::StuckAt: pressed = f.value != 0.0; break;
      case InputFaultKind::Intermittent:
        if (intermittently_lost(f, now_us)) return FaultEffect::Lost;
        break;
      case InputFaultKind::Disconnect: return FaultEffect::Lost;
      default: continue;  // refused at injection
    }
    effect = FaultEffect::Changed;
  }
  return effect;
}

FaultEffect apply_switch_faults(std::span<const InputFault> faults, std::size_t control, int64_t now_us,
                                uint8_t& position) {
  FaultEffect effect = FaultEffect::None;
  for (const InputFault& f : faults) {
    if (f.control != control || !f.active(now_us)) continue;
    switch (f.kind) {
      case InputFaultKind::StuckAt: position = static_cast<uint8_t>(std::clamp(f.value, 0.0, 254.0)); break;
      case InputFaultKind::OutOfRange: position = 254; return FaultEffect::OutOfRange;
      case InputFaultKind::Intermittent:
        if (intermittently_lost(f, now_us)) return FaultEffect::Lost;
        break;
      case InputFaultKind::Disconnect: return FaultEffect::Lost;
      default: continue;
    }
    effect = FaultEffect::Changed;
  }
  return effect;
}

}  // namespace rise::hil
