#include "instructor/app/sound_output.hpp"

#include <alsa/asoundlib.h>

#include <cerrno>
#include <cmath>
#include <cstring>

namespace rise::sound {

int16_t to_s16(float v) {
  const float c = v > 1.0f ? 1.0f : v < -1.0f ? -1.0f : v;
  return static_cast<int16_t>(std::lround(c * 32767.0f));
}

AlsaOutput::~AlsaOutput() {
  if (pcm_) snd_pcm_close(pcm_);
}

std::string AlsaOutput::open(const std::string& device, int rate, unsigned latency_us) {
  if (int e = snd_pcm_open(&pcm_, device.c_str(), SND_PCM_STREAM_PLAYBACK, 0); e < 0) {
    pcm_ = nullptr;
    return std::string("cannot open: ") + snd_strerror(e) +
           (e == -ENOENT ? " (no such PCM or sound card; `aplay -L` lists them)" : "");
  }
  // Stereo: every device takes it; ALSA's plug layer (soft_resample) converts rate and format.
  if (int e = snd_pcm_set_params(pcm_, SND_PCM_FORMAT_S16_LE, SND_PCM_ACCESS_RW_INTERLEAVED, 2,
                                 static_cast<unsigned>(rate), 1, latency_us);
      e < 0) {
    snd_pcm_close(pcm_);
    pcm_ = nullptr;
    return std::string("cannot play 16-bit stereo at ") + std::to_string(rate) + " Hz: " + snd_strerror(e);
  }
  return "";
}

std::string AlsaOutput::write(const float* mono, std::size_t frames) {
  buffer_.resize(frames * 2);
  for (std::size_t i = 0; i < frames; ++i) buffer_[2 * i] = buffer_[2 * i + 1] = to_s16(mono[i]);
  std::size_t done = 0;
  while (done < frames) {
    const snd_pcm_sframes_t n = snd_pcm_writei(pcm_, buffer_.data() + 2 * done, frames - done);
    if (n < 0) {
      // An underrun (EPIPE) or a suspend: recover and go on; anything else ends playing.
      if (const int e = snd_pcm_recover(pcm_, static_cast<int>(n), 1); e < 0) return snd_strerror(e);
      continue;
    }
    done += static_cast<std::size_t>(n);
  }
  return "";
}

void AlsaOutput::close() {
  if (!pcm_) return;
  snd_pcm_drain(pcm_);
  snd_pcm_close(pcm_);
  pcm_ = nullptr;
}

namespace {
void put32(std::ofstream& o, uint32_t v) {
  const char b[4] = {static_cast<char>(v), static_cast<char>(v >> 8), static_cast<char>(v >> 16), static_cast<char>(v >> 24)};
  o.write(b, 4);
}
void put16(std::ofstream& o, uint16_t v) {
  const char b[2] = {static_cast<char>(v), static_cast<char>(v >> 8)};
  o.write(b, 2);
}
}  // namespace

std::string WavFile::open(const std::string& path, int rate) {
  out_.open(path, std::ios::binary | std::ios::trunc);
  if (!out_) return std::strerror(errno);
  rate_ = rate;
  frames_ = 0;
  header();
  return out_ ? "" : std::strerror(errno);
}

// RIFF/WAVE, PCM, mono, 16-bit; the sizes are those of the frames so far.
void WavFile::header() {
  const uint32_t data = static_cast<uint32_t>(frames_ * 2);
  out_.seekp(0);
  out_.write("RIFF", 4);
  put32(out_, 36 + data);
  out_.write("WAVEfmt ", 8);
  put32(out_, 16);
  put16(out_, 1);  // PCM
  put16(out_, 1);  // mono
  put32(out_, static_cast<uint32_t>(rate_));
  put32(out_, static_cast<uint32_t>(rate_) * 2);
  put16(out_, 2);
  put16(out_, 16);
  out_.write("data", 4);
  put32(out_, data);
}

void WavFile::write(const float* mono, std::size_t frames) {
  if (!out_.is_open()) return;
  for (std::size_t i = 0; i < frames; ++i) put16(out_, static_cast<uint16_t>(to_s16(mono[i])));
  frames_ += frames;
}

void WavFile::close() {
  if (!out_.is_open()) return;
  header();
  out_.close();
}

}  // namespace rise::sound
