#include "instructor/sound_synth.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <initializer_list>

namespace rise::sound {
namespace {

constexpr double kTwoPi = 6.283185307179586;
// A full-scale continuous voice (gain 1) has this RMS level: its partials'
// peaks stay under 1, so gain alone sets the level (nothing clips).
constexpr double kToneRms = 0.4;

class Noise {
 public:
  explicit Noise(uint32_t seed) : s_(seed ? seed : 1u) {}
  float next() {  // xorshift32, -1..1
    s_ ^= s_ << 13;
    s_ ^= s_ >> 17;
    s_ ^= s_ << 5;
    return static_cast<float>(s_) / 2147483648.0f - 1.0f;
  }

 private:
  uint32_t s_;
};

// A held tone: partials of f0 (amplitudes `partials`, scaled to kToneRms) with
// a slow amplitude wobble (a motor's cogging) that follows the pitch too.
class Tone : public Waveform {
 public:
  Tone(int rate, double f0, std::initializer_list<double> partials, double wobble_hz, double wobble_depth)
      : rate_(rate), f0_(f0), partials_(partials), wobble_hz_(wobble_hz), wobble_depth_(wobble_depth) {
    double power = 0.0;
    for (double a : partials_) power += a * a / 2.0;
    // The wobble's mean square: 1 + depth²/2 of the tone's.
    scale_ = kToneRms / std::sqrt(power * (1.0 + wobble_depth_ * wobble_depth_ / 2.0));
  }
  float next(float pitch) override {
    phase_ = std::fmod(phase_ + f0_ * pitch / rate_, 1.0);
    wobble_ = std::fmod(wobble_ + wobble_hz_ * pitch / rate_, 1.0);
    double v = 0.0;
    for (std::size_t k = 0; k < partials_.size(); ++k) v += partials_[k] * std::sin(kTwoPi * static_cast<double>(k + 1) * phase_);
    return static_cast<float>(scale_ * v * (1.0 + wobble_depth_ * std::sin(kTwoPi * wobble_)));
  }

 private:
  int rate_;
  double f0_;
  std::vector<double> partials_;
  double wobble_hz_, wobble_depth_;
  double scale_ = 1.0, phase_ = 0.0, wobble_ = 0.0;
};

// A one-shot: body(t, noise) over `seconds` of its own time (pitch speeds it up).
class Shot : public Waveform {
 public:
  using Body = std::function<float(double t, Noise& noise)>;
  Shot(int rate, double seconds, uint32_t seed, Body body)
      : rate_(rate), seconds_(seconds), noise_(seed), body_(std::move(body)) {}
  float next(float pitch) override {
    const float v = t_ < seconds_ ? body_(t_, noise_) : 0.0f;
    t_ += static_cast<double>(pitch) / rate_;
    return v;
  }
  std::size_t length() const override { return static_cast<std::size_t>(std::ceil(seconds_ * rate_)); }

 private:
  int rate_;
  double seconds_;
  Noise noise_;
  Body body_;
  double t_ = 0.0;
};

double ring(double t, double hz, double tau) { return std::sin(kTwoPi * hz * t) * std::exp(-t / tau); }

// An impact: a click of noise and the struck material's ringing partials.
Shot::Body impact(double click_tau, std::vector<double> partials_hz, double ring_tau, double ring_level) {
  return [=](double t, Noise& n) {
    double v = 0.5 * n.next() * std::exp(-t / click_tau);
    for (double hz : partials_hz) v += ring_level * ring(t, hz, ring_tau) / static_cast<double>(partials_hz.size());
    return static_cast<float>(v);
  };
}

// A door's creak: a rough sawtooth whose pitch wanders, in stick-slip bursts.
float creak(double t, double seconds, Noise& n) {
  const double phase = 170.0 * t - 55.0 / (kTwoPi * 1.3) * std::cos(kTwoPi * 1.3 * t);  // ∫ 170 + 55 sin(2π·1.3 t)
  const double saw = 2.0 * (phase - std::floor(phase)) - 1.0;
  const double bursts = 0.55 + 0.45 * std::sin(kTwoPi * 21.0 * t);
  const double env = std::min({1.0, t / 0.01, (seconds - t) / 0.2});
  return static_cast<float>(0.5 * env * bursts * (saw + 0.15 * n.next()));
}

// A crash: noise through a low-pass that opens and closes, with rattles.
Shot::Body crash(double decay_tau) {
  auto low = std::make_shared<double>(0.0);
  return [=](double t, Noise& n) {
    const double cutoff = 0.05 + 0.25 * std::exp(-t / 0.08);
    *low += cutoff * (n.next() - *low);
    const double rattle = std::fmod(t, 0.07) < 0.01 ? 0.3 * n.next() * std::exp(-t / 0.4) : 0.0;
    return static_cast<float>((0.9 * *low + rattle) * std::exp(-t / decay_tau));
  };
}

// A horn: two square-ish tones a third apart, with a short attack and release.
float horn(double t, double seconds) {
  const double env = std::min({1.0, t / 0.01, (seconds - t) / 0.05});
  double v = 0.0;
  for (double hz : {392.0, 494.0})
    for (int k = 1; k <= 5; k += 2) v += std::sin(kTwoPi * hz * k * t) / k;
  return static_cast<float>(0.3 * env * v);
}

std::unique_ptr<Waveform> continuous_waveform(const std::string& s, int rate) {
  if (s == "wheel_motor_whine") return std::make_unique<Tone>(rate, 220.0, std::initializer_list<double>{1.0, 0.5, 0.3}, 30.0, 0.2);
  if (s == "tracked_motor_hum") return std::make_unique<Tone>(rate, 70.0, std::initializer_list<double>{1.0, 0.7, 0.5, 0.3}, 12.0, 0.3);
  if (s == "servo_whine") return std::make_unique<Tone>(rate, 520.0, std::initializer_list<double>{1.0, 0.3}, 8.0, 0.1);
  if (s == "servo_small") return std::make_unique<Tone>(rate, 880.0, std::initializer_list<double>{1.0, 0.2}, 6.0, 0.1);
  return nullptr;
}

std::unique_ptr<Waveform> one_shot_waveform(const std::string& s, int rate, uint32_t seed) {
  if (s == "plastic_impact") return std::make_unique<Shot>(rate, 0.2, seed, impact(0.015, {900.0, 1730.0}, 0.04, 0.4));
  if (s == "metal_impact") return std::make_unique<Shot>(rate, 0.8, seed, impact(0.01, {1250.0, 2710.0, 3900.0}, 0.22, 0.45));
  if (s == "metal_snap") return std::make_unique<Shot>(rate, 0.35, seed, impact(0.004, {2200.0}, 0.07, 0.45));
  if (s == "door_creak") return std::make_unique<Shot>(rate, 0.9, seed, [](double t, Noise& n) { return creak(t, 0.9, n); });
  if (s == "crash") return std::make_unique<Shot>(rate, 1.2, seed, crash(0.3));
  if (s == "heavy_crash") return std::make_unique<Shot>(rate, 1.8, seed, crash(0.5));
  if (s == "horn") return std::make_unique<Shot>(rate, 0.7, seed, [](double t, Noise&) { return horn(t, 0.7); });
  return nullptr;
}

}  // namespace

bool known_sample(const std::string& sample) {
  return continuous_waveform(sample, 8000) != nullptr || one_shot_waveform(sample, 8000, 1) != nullptr;
}

std::unique_ptr<Waveform> make_waveform(const std::string& sample, bool continuous, int rate, uint32_t seed) {
  if (auto w = continuous ? continuous_waveform(sample, rate) : one_shot_waveform(sample, rate, seed)) return w;
  // A name this player does not know still sounds: a plain tone, or a beep.
  if (continuous) return std::make_unique<Tone>(rate, 300.0, std::initializer_list<double>{1.0}, 0.0, 0.0);
  return std::make_unique<Shot>(rate, 0.2, seed, [](double t, Noise&) {
    return static_cast<float>(0.5 * std::sin(kTwoPi * 880.0 * t) * std::min(1.0, (0.2 - t) / 0.02));
  });
}

Synth::Synth(int rate)
    : rate_(rate), glide_(static_cast<float>(1.0 - std::exp(-4.6 / (kGlideS * rate)))) {}  // 99 % in kGlideS

void Synth::cue(const Cue& c) {
  if (c.continuous) {
    auto it = held_.find(c.name);
    if (it == held_.end()) {
      if (c.gain <= 0.0f) return;  // silent and not sounding: nothing to fade
      Held h;
      h.wave = make_waveform(c.sample, true, rate_, seeds_++);
      h.pitch = c.pitch;  // a new voice starts at its pitch, and fades in
      it = held_.emplace(c.name, std::move(h)).first;
    }
    it->second.target_gain = std::clamp(c.gain, 0.0f, 1.0f);
    it->second.target_pitch = std::max(c.pitch, 0.01f);
    it->second.updated = frame_;
    return;
  }
  if (c.gain <= 0.0f) return;
  Shot s;
  s.wave = make_waveform(c.sample, false, rate_, seeds_++);
  s.gain = std::clamp(c.gain, 0.0f, 1.0f);
  s.pitch = std::max(c.pitch, 0.01f);
  s.left = static_cast<std::size_t>(std::ceil(static_cast<double>(s.wave->length()) / s.pitch));
  constexpr std::size_t kMaxShots = 32;  // a pile-up of impacts drops the oldest
  if (shots_.size() == kMaxShots) shots_.erase(shots_.begin());
  shots_.push_back(std::move(s));
}

float Synth::render_held(Held& h) {
  if (frame_ - h.updated > static_cast<uint64_t>(kStaleS * rate_)) h.target_gain = 0.0f;
  h.gain += (h.target_gain - h.gain) * glide_;
  h.pitch += (h.target_pitch - h.pitch) * glide_;
  return h.gain * h.wave->next(h.pitch);
}

void Synth::render(float* out, std::size_t frames) {
  for (std::size_t i = 0; i < frames; ++i, ++frame_) {
    float v = 0.0f;
    for (auto& [name, h] : held_) v += render_held(h);
    for (auto& s : shots_) {
      if (s.left == 0) continue;
      v += s.gain * s.wave->next(s.pitch);
      --s.left;
    }
    out[i] = std::clamp(v, -1.0f, 1.0f);
  }
  // Faded out (below 16-bit's least step) or played to the end: gone, so silence is exact.
  std::erase_if(held_, [](const auto& kv) { return kv.second.target_gain == 0.0f && kv.second.gain < 1e-5f; });
  std::erase_if(shots_, [](const Shot& s) { return s.left == 0; });
}

}  // namespace rise::sound
