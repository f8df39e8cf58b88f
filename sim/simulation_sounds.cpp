// The robot files' sound cues (sim/sound_description.hpp): one-shots set
// off by events and buttons, and the continuous cues that follow the drive,
// the arm and the gripper.

#include <ode/ode.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "sim/simulation_impl.hpp"

namespace rise::sim {
namespace {

constexpr std::size_t kMaxPendingSounds = 1024;

}  // namespace

// The robot file's one-shot cues for `trigger` (button: that button; impact:
// the collision's approach speed).
void Simulation::Impl::cue(const Robot& r, SoundTrigger trigger, const std::string& detail, double impact_mps,
                           const std::string& button) {
  for (const auto& c : r.desc.sounds) {
    if (c.trigger != trigger || (trigger == SoundTrigger::Button && c.button != button)) continue;
    double gain = c.gain;
    if (trigger == SoundTrigger::CollisionStarted) {
      if (impact_mps < c.min_impact_mps) continue;
      if (c.gain_per_mps > 0.0) gain = std::min(c.gain, c.gain_per_mps * impact_mps);
    }
    if (sounds.size() >= kMaxPendingSounds) return;
    sounds.push_back(SoundCue{time_s(), r.id, c.name, c.sample, false, gain, c.pitch, detail});
  }
}

// A door's cue goes to the robots touching the door, or, when none does,
// to every robot.
void Simulation::Impl::door_cue(const std::string& door, SoundTrigger trigger, const std::string& detail) {
  std::vector<bool> near(robots.size(), false);
  bool any = false;
  for (const auto& [key, c] : active) {
    if (key.second != door || c.robot_a < 0) continue;
    near[static_cast<std::size_t>(c.robot_a)] = true;
    any = true;
  }
  for (std::size_t i = 0; i < robots.size(); ++i)
    if (near[i] || !any) cue(*robots[i], trigger, detail);
}

// The value a continuous cue follows (sim/sound_description.hpp).
double Simulation::Impl::sound_source_value(const Robot& r, SoundSource source) {
  switch (source) {
    case SoundSource::DriveSpeed: {
      const auto [left, right] = side_speeds_mps(r);
      return (std::fabs(left) + std::fabs(right)) / 2;
    }
    case SoundSource::ArmRate: {
      double rate = 0.0;
      for (const auto& a : r.arm_joints)
        if (a.joint && !a.slider) rate = std::max(rate, std::fabs(dJointGetHingeAngleRate(a.joint)));
      return rate;
    }
    case SoundSource::GripperSpeed:
      for (const auto& a : r.arm_joints)
        if (a.joint && a.slider) return std::fabs(dJointGetSliderPositionRate(a.joint));
      return 0.0;
  }
  return 0.0;
}

// The robot's continuous cues now, in file order (silent ones with gain 0).
std::vector<SoundCue> Simulation::Impl::continuous_cues(const Robot& r, double time_s) {
  std::vector<SoundCue> cues;
  for (const auto& c : r.desc.sounds) {
    if (!c.source) continue;
    // Linear from [0] at rest to [1] at full_at; silent at or below silent_below.
    const double value = sound_source_value(r, *c.source);
    const double x = std::min(1.0, value / c.full_at);
    const bool audible = value > c.silent_below;
    char detail[64];
    std::snprintf(detail, sizeof detail, "%s %.3f", to_string(*c.source), value);
    cues.push_back(SoundCue{time_s, r.id, c.name, c.sample, true,
                            audible ? c.gain_range[0] + (c.gain_range[1] - c.gain_range[0]) * x : 0.0,
                            c.pitch_range[0] + (c.pitch_range[1] - c.pitch_range[0]) * x, detail});
  }
  return cues;
}

std::vector<SoundCue> Simulation::take_sound_cues() {
  std::vector<SoundCue> out;
  out.swap(impl_->sounds);
  return out;
}

}  // namespace rise::sim
