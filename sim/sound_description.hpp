#pragma once

// The robot file's optional `sounds` section: the cues a sound player plays
// for the robot — continuous ones (an engine hum, arm servos) whose gain and
// pitch follow a robot quantity, and one-shots set off by events (an impact,
// a joint breaking, a door opening, the horn button).

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace rise::sim {

/// What a continuous cue follows.
enum class SoundSource {
  DriveSpeed,    ///< m/s: the mean |speed| of the left and right belts (tracks) or wheel rims
  ArmRate,       ///< rad/s: the largest |rate| of the arm's revolute joints
  GripperSpeed,  ///< m/s: |gripper finger rate|
};

/// What sets off a one-shot cue.
enum class SoundTrigger {
  CollisionStarted,  ///< one of the robot's parts starts touching something; gain may follow the impact speed
  JointBroken,       ///< one of the robot's joints breaks
  DoorOpened,        ///< a door the robot touches (or any door, when no robot touches it) opens
  DoorClosed,
  TippedOver,
  StairsClimbed,
  RegionEntered,
  Button,            ///< a panel button is pressed (its rising edge), e.g. a horn
};

struct SoundCueDescription {
  std::string name;    ///< the cue's key in `sounds`
  std::string sample;  ///< what the player plays (a file or bank name); default: the name

  // Continuous (`source`): gain and pitch go linearly from [0] at a source
  // value of 0 to [1] at full_at and beyond; at or below silent_below the
  // cue is silent (gain 0).
  std::optional<SoundSource> source;
  double full_at = 1.0;
  double silent_below = 0.0;
  std::array<double, 2> gain_range{0.0, 1.0};
  std::array<double, 2> pitch_range{1.0, 1.0};

  // One-shot (`on`).
  std::optional<SoundTrigger> trigger;
  std::string button;          ///< SoundTrigger::Button: the panel button
  double gain = 1.0;           ///< 0..1; with gain_per_mps, the most an impact gives
  double pitch = 1.0;          ///< playback rate, 1 = as recorded
  double gain_per_mps = 0.0;   ///< collision_started: gain = min(gain, gain_per_mps · impact speed); 0 = fixed gain
  double min_impact_mps = 0.0; ///< collision_started: slower impacts make no sound

  bool continuous() const { return source.has_value(); }
  bool operator==(const SoundCueDescription&) const = default;
};

const char* to_string(SoundSource source);
const char* to_string(SoundTrigger trigger);

}  // namespace rise::sim
