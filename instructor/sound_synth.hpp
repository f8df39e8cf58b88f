#pragma once

// rise::sound — the robot's sound cues (SoundCue on rise/<id>/sound, the
// robot file's `sounds:` section) made audible without sample files: each
// sample name is synthesised (a motor's whine or hum, an impact, a door's
// creak, a crash, a horn; an unknown name a plain tone or beep). Continuous
// cues hold a level: their gain and pitch glide to each new message's and
// fade out when a message says gain 0 or none comes for a while; one-shots
// start at once and play to their end. Everything is mixed into one mono
// stream. Pure: no I/O, no clock but the frames rendered (rise-sound plays it).

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace rise::sound {

/// One SoundCue as the synthesiser needs it.
struct Cue {
  std::string name;    ///< the cue's key in the robot file (a continuous voice per name)
  std::string sample;  ///< what to play: picks the waveform
  bool continuous = false;
  float gain = 0.0f;   ///< 0..1
  float pitch = 1.0f;  ///< playback rate, 1 = the sample's own
};

/// A sample's waveform: a source of samples at a rate, for one voice.
class Waveform {
 public:
  virtual ~Waveform() = default;
  /// The next sample at `pitch` (about -1..1 for a full-scale voice).
  virtual float next(float pitch) = 0;
  /// One-shots: frames until the sound has died away (at pitch 1).
  virtual std::size_t length() const { return 0; }
};

/// The waveform for `sample` at `rate` Hz; `continuous` picks a held tone
/// for names it does not know, else a short beep. `seed` varies the noise.
std::unique_ptr<Waveform> make_waveform(const std::string& sample, bool continuous, int rate, uint32_t seed);

/// Whether `sample` has a waveform of its own (not the fallback tone).
bool known_sample(const std::string& sample);

class Synth {
 public:
  /// How long a continuous level glides to a new one (a message comes every 20 ms).
  static constexpr double kGlideS = 0.05;
  /// A continuous cue with no message for this long fades out (its publisher is gone).
  static constexpr double kStaleS = 0.5;

  explicit Synth(int rate);

  /// A cue arrives: updates its continuous voice or starts a one-shot.
  void cue(const Cue& c);
  /// Mixes the next `frames` samples into `out` (overwritten), clipped to -1..1.
  void render(float* out, std::size_t frames);

  /// Voices sounding now (continuous ones not yet faded out, one-shots not ended).
  std::size_t voices() const { return held_.size() + shots_.size(); }
  int rate() const { return rate_; }

 private:
  struct Held {
    std::unique_ptr<Waveform> wave;
    float gain = 0.0f, pitch = 1.0f;                // now
    float target_gain = 0.0f, target_pitch = 1.0f;  // the last message's
    uint64_t updated = 0;                           // frame of the last message
  };
  struct Shot {
    std::unique_ptr<Waveform> wave;
    float gain = 0.0f, pitch = 1.0f;
    std::size_t left = 0;  // frames
  };
  float render_held(Held& h);

  int rate_;
  float glide_;  // per-frame step of the one-pole glide
  uint64_t frame_ = 0;
  uint32_t seeds_ = 1;
  std::map<std::string, Held> held_;
  std::vector<Shot> shots_;
};

}  // namespace rise::sound
