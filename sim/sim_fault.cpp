#include "sim/sim_fault.hpp"

#include <cmath>
#include <numbers>

namespace rise::sim {

const char* to_string(SimFaultKind kind) {
  switch (kind) {
    case SimFaultKind::MotorFailure: return "motor_failure";
    case SimFaultKind::MotorWeakness: return "motor_weakness";
    case SimFaultKind::TrackSlip: return "track_slip";
    case SimFaultKind::WeakJoint: return "weak_joint";
    case SimFaultKind::CameraBlackout: return "camera_blackout";
    case SimFaultKind::ScannerNoise: return "scanner_noise";
    case SimFaultKind::ScannerDropout: return "scanner_dropout";
  }
  return "?";
}

std::optional<SimFaultKind> parse_sim_fault_kind(std::string_view name) {
  for (auto k : {SimFaultKind::MotorFailure, SimFaultKind::MotorWeakness, SimFaultKind::TrackSlip,
                 SimFaultKind::WeakJoint, SimFaultKind::CameraBlackout, SimFaultKind::ScannerNoise,
                 SimFaultKind::ScannerDropout})
    if (name == to_string(k)) return k;
  return std::nullopt;
}

double fault_uniform(uint64_t seed, uint64_t index) {
  const auto mix = [](uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
  };
  return static_cast<double>(mix(mix(seed) ^ (index * 0xd1b54a32d192ed03ull)) >> 11) * 0x1.0p-53;
}

double fault_normal(uint64_t seed, uint64_t index) {
  const double u1 = 1.0 - fault_uniform(seed, 2 * index);
  const double u2 = fault_uniform(seed, 2 * index + 1);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

}  // namespace rise::sim
