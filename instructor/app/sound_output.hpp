#pragma once

// Where rise-sound's mix goes: an ALSA PCM (any name ALSA knows: "default",
// "hw:0", "null", "file:FILE=out.raw", ...) and a WAV file.

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

typedef struct _snd_pcm snd_pcm_t;

namespace rise::sound {

/// Mono float frames → 16-bit stereo on an ALSA PCM (ALSA's plug layer
/// converts for the device). Blocking writes; an underrun is recovered.
class AlsaOutput {
 public:
  AlsaOutput() = default;
  AlsaOutput(const AlsaOutput&) = delete;
  AlsaOutput& operator=(const AlsaOutput&) = delete;
  ~AlsaOutput();

  /// Opens `device` at `rate` Hz with `latency_us` of buffer; "" or the
  /// reason it cannot (ALSA's words).
  std::string open(const std::string& device, int rate, unsigned latency_us);
  /// Plays `frames` samples; "" or why not (after a failed recovery).
  std::string write(const float* mono, std::size_t frames);
  /// Lets the device play what it holds, then closes it.
  void close();

 private:
  snd_pcm_t* pcm_ = nullptr;
  std::vector<int16_t> buffer_;
};

/// A 16-bit mono PCM WAV file, its sizes written on close().
class WavFile {
 public:
  /// "" or why the file cannot be written.
  std::string open(const std::string& path, int rate);
  void write(const float* mono, std::size_t frames);
  /// Writes the header's sizes and closes; the file is complete after it.
  void close();
  uint64_t frames() const { return frames_; }

 private:
  void header();
  std::ofstream out_;
  int rate_ = 0;
  uint64_t frames_ = 0;
};

/// -1..1 → 16-bit, rounded and saturated.
int16_t to_s16(float v);

}  // namespace rise::sound
