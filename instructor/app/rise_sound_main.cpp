// rise-sound: the robot's sound for a station without a browser. Listens to
// SoundCue on rise/<id>/sound (rise-sim's cues, the robot file's `sounds:`),
// synthesises each sample (rise::sound) and plays the mix through ALSA, and
// with --out writes the same mix to a WAV file.

#include <CLI/CLI.hpp>
#include <alsa/asoundlib.h>
#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include <chrono>
#include <csignal>
#include <cstdarg>
#include <optional>
#include <string>
#include <vector>

#include "cli/command_line.hpp"
#include "instructor/app/sound_output.hpp"
#include "instructor/sound_synth.hpp"
#include "msgs/channels.hpp"
#include "msgs/lcm_decode.hpp"
#include "rise_msgs/SoundCue.hpp"

namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

struct Options {
  std::string id;
  std::string lcm_url = rise::msgs::kDefaultLcmUrl;
  std::string device = "default";
  std::string out;
  double seconds = 0.0;  // 0: until SIGINT / SIGTERM
  int rate = 48000;
  double lead_ms = 60.0;
  std::string log_level = "info";
};

void add_options(CLI::App& app, Options& o) {
  app.add_option("--id", o.id, "the trainee / robot id: plays rise/<id>/sound")->required();
  app.add_option("--lcm", o.lcm_url, "LCM URL")->capture_default_str();
  app.add_option("--device", o.device, "ALSA PCM to play on (default, hw:0, null, file:FILE=x.raw, ...)")
      ->capture_default_str();
  app.add_option("--out", o.out, "also write the mix to this WAV file (16-bit mono)");
  app.add_option("--seconds", o.seconds, "stop after this long (0: until Ctrl-C)")->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--rate", o.rate, "sample rate, Hz")->check(CLI::Range(8000, 192000))->capture_default_str();
  app.add_option("--lead-ms", o.lead_ms, "how far ahead of the clock the mix is made (the delay heard)")
      ->check(CLI::Range(5.0, 1000.0))->capture_default_str();
  app.add_option("--log-level", o.log_level, "trace, debug, info, warn, error")->capture_default_str();
}

// ALSA prints its own lines on stderr (e.g. "Unknown PCM foo"); the program
// says it once, in its own words.
void quiet_alsa(const char*, int, const char*, int, const char*, ...) {}

struct Counts {
  int cues = 0, one_shots = 0;
};

struct CueHandler {
  rise::sound::Synth* synth;
  Counts* counts;
  void on(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::SoundCue* m) {
    synth->cue({m->name, m->sample, m->continuous != 0, m->gain, m->pitch});
    ++counts->cues;
    if (!m->continuous) {
      ++counts->one_shots;
      spdlog::debug("{}: {} gain {:.2f} ({})", m->name, m->sample, m->gain, m->detail);
    }
  }
};

// Makes the mix in 5 ms blocks, paced by the monotonic clock (`lead` ahead of
// it): a null or file device takes data as fast as it comes, a sound card
// blocks when its buffer is full. Returns "" or why playing stopped.
std::string play(const Options& o, lcm::LCM& lcm, rise::sound::Synth& synth, rise::sound::AlsaOutput& alsa,
                 rise::sound::WavFile* wav) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  const std::size_t block = static_cast<std::size_t>(o.rate / 200);
  std::vector<float> mix(block);
  uint64_t made = 0;
  const uint64_t total = static_cast<uint64_t>(o.seconds * o.rate);
  while (!g_stop && (total == 0 || made < total)) {
    lcm.handleTimeout(2);
    const double now_s = std::chrono::duration<double>(Clock::now() - start).count();
    const auto due = static_cast<uint64_t>((now_s + o.lead_ms / 1000.0) * o.rate);
    while (made < due && (total == 0 || made < total)) {
      synth.render(mix.data(), block);
      if (auto e = alsa.write(mix.data(), block); !e.empty()) return e;
      if (wav) wav->write(mix.data(), block);
      made += block;
    }
  }
  return "";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rise-sound: plays a robot's sound cues (SoundCue on rise/<id>/sound) through ALSA, synthesised"};
  Options o;
  add_options(app, o);
  if (const auto code = rise::cli::parse_command_line(app, "rise-sound", argc, argv)) return *code;
  spdlog::set_level(spdlog::level::from_str(o.log_level));
  snd_lib_error_set_handler(quiet_alsa);
  rise::sound::AlsaOutput alsa;
  if (const auto e = alsa.open(o.device, o.rate, static_cast<unsigned>(o.lead_ms * 2000)); !e.empty()) {
    spdlog::error("ALSA device '{}': {}", o.device, e);
    return 1;
  }
  std::optional<rise::sound::WavFile> wav;
  if (!o.out.empty()) {
    wav.emplace();
    if (const auto e = wav->open(o.out, o.rate); !e.empty()) {
      spdlog::error("cannot write {}: {}", o.out, e);
      return 1;
    }
  }
  lcm::LCM lcm(o.lcm_url);
  if (!lcm.good()) {
    spdlog::error("cannot open LCM at {}", o.lcm_url);
    return 1;
  }
  rise::sound::Synth synth(o.rate);
  Counts counts;
  CueHandler handler{&synth, &counts};
  const std::string channel = rise::msgs::sound_channel(o.id);
  rise::msgs::subscribe<&CueHandler::on>(lcm, channel, &handler)->setQueueCapacity(200);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  spdlog::info("rise-sound ready: {} → ALSA '{}' at {} Hz{}", channel, o.device, o.rate, o.out.empty() ? "" : ", " + o.out);
  const std::string error = play(o, lcm, synth, alsa, wav ? &*wav : nullptr);
  if (wav) wav->close();
  if (!error.empty()) {
    spdlog::error("ALSA device '{}': {}", o.device, error);
    return 1;
  }
  alsa.close();
  spdlog::info("rise-sound: {} cues ({} one-shots){}", counts.cues, counts.one_shots,
               wav ? ", " + std::to_string(wav->frames()) + " frames in " + o.out : "");
  return 0;
}
