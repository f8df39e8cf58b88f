// rise::sound and rise-sound: the synthesiser on its own (a continuous cue's
// level follows its gain and glides, its pitch sets the frequency, a stale
// one fades out, a one-shot starts at once and ends, voices mix by adding,
// every shipped robot's sample has a waveform), and the program as a station
// runs it: real SoundCue messages over LCM (gain 0.2, 0.8, then 0, then a
// horn) played through ALSA's `file` plugin and written with --out, the level
// of each segment measured with sox; a device ALSA does not know is one line
// and exit 1.

#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "instructor/sound_synth.hpp"
#include "msgs/channels.hpp"
#include "msgs/clock.hpp"
#include "process/child_process.hpp"
#include "rise_msgs/SoundCue.hpp"
#include "sim/robot_description.hpp"
#include "tests/process_support.hpp"

namespace fs = std::filesystem;
using rise::process::ChildProcess;
using rise::sound::Cue;
using rise::sound::Synth;

namespace {
constexpr int kRate = 48000;
const std::string kBin = std::string(RISE_BINARY_DIR) + "/bin";

std::vector<float> render(Synth& s, double seconds) {
  std::vector<float> out(static_cast<std::size_t>(seconds * s.rate()));
  s.render(out.data(), out.size());
  return out;
}

double rms(const std::vector<float>& x, std::size_t from = 0, std::size_t to = std::numeric_limits<std::size_t>::max()) {
  to = std::min(to, x.size());
  double sum = 0.0;
  for (std::size_t i = from; i < to; ++i) sum += static_cast<double>(x[i]) * x[i];
  return to > from ? std::sqrt(sum / static_cast<double>(to - from)) : 0.0;
}

// The fundamental by autocorrelation (lags for 50 Hz .. 1.2 kHz).
double fundamental_hz(const std::vector<float>& x) {
  std::size_t best = 0;
  double best_sum = -1.0;
  for (std::size_t lag = kRate / 1200; lag <= kRate / 50; ++lag) {
    double sum = 0.0;
    for (std::size_t i = 0; i + lag < 9600; ++i) sum += static_cast<double>(x[i]) * x[i + lag];
    if (sum > best_sum) best_sum = sum, best = lag;
  }
  return static_cast<double>(kRate) / static_cast<double>(best);
}

Cue whine(float gain, float pitch = 1.0f) { return {"wheel_motors", "wheel_motor_whine", true, gain, pitch}; }
}  // namespace

namespace {
// A continuous cue as rise-sim sends it: again every 20 ms, for `seconds`.
std::vector<float> hold(Synth& s, const Cue& c, double seconds) {
  std::vector<float> out;
  std::vector<float> block(kRate / 50);
  for (int i = 0; i < static_cast<int>(seconds * 50); ++i) {
    s.cue(c);
    s.render(block.data(), block.size());
    out.insert(out.end(), block.begin(), block.end());
  }
  return out;
}
}  // namespace

TEST_CASE("a continuous cue's level follows its gain, gliding, and silence follows gain 0", "[instructor]") {
  Synth s(kRate);
  const auto a = hold(s, whine(0.2f), 1.0);
  const auto b = hold(s, whine(0.8f), 1.0);
  const auto c = hold(s, whine(0.0f), 1.0);
  const double ra = rms(a, kRate / 4), rb = rms(b, kRate / 4);
  CHECK(rb / ra == Approx(4.0).epsilon(0.03));
  CHECK(ra == Approx(0.2 * 0.4).epsilon(0.05));  // kToneRms 0.4 at gain 1
  // The step glides: the first 5 ms after it are still far from the new level, 50 to 100 ms there.
  CHECK(rms(b, 0, 240) < 0.6 * rb);
  CHECK(rms(b, 2400, 4800) > 0.9 * rb);
  // Silent after the fade, exactly: the voice is gone.
  CHECK(rms(c, 0, 240) > 0.0);
  CHECK(rms(c, kRate / 4) == 0.0);
  CHECK(s.voices() == 0);
}

TEST_CASE("a continuous cue's pitch sets its frequency, and a cue that stops coming fades out", "[instructor]") {
  Synth s(kRate);
  hold(s, whine(0.5f, 1.0f), 0.2);
  CHECK(fundamental_hz(hold(s, whine(0.5f, 1.0f), 0.3)) == Approx(220.0).epsilon(0.02));
  hold(s, whine(0.5f, 1.8f), 0.2);
  CHECK(fundamental_hz(hold(s, whine(0.5f, 1.8f), 0.3)) == Approx(396.0).epsilon(0.02));
  // No message from now on: still sounding before kStaleS, gone after it.
  render(s, 0.4);
  CHECK(s.voices() == 1);
  render(s, 0.4);
  CHECK(s.voices() == 0);
}

TEST_CASE("a one-shot starts at once and ends; voices mix by adding", "[instructor]") {
  Synth horn(kRate), motor(kRate), both(kRate);
  horn.cue({"horn", "horn", false, 0.8f, 1.0f});
  const auto h = render(horn, 1.0);
  CHECK(rms(h, 0, 480) > 0.05);    // within the first 10 ms (its attack)
  CHECK(rms(h, 0, 33600) > 0.1);   // 0.7 s long
  CHECK(rms(h, 33600) == 0.0);
  CHECK(horn.voices() == 0);
  const auto m = hold(motor, whine(0.3f), 1.0);
  both.cue({"horn", "horn", false, 0.8f, 1.0f});
  const auto mix = hold(both, whine(0.3f), 1.0);
  double worst = 0.0;
  for (std::size_t i = 0; i < mix.size(); ++i) worst = std::max(worst, static_cast<double>(std::abs(mix[i] - h[i] - m[i])));
  CHECK(worst < 1e-5);
}

TEST_CASE("every sample the shipped robots name has a waveform of its own", "[instructor]") {
  int n = 0;
  for (const auto* file : {"skid4.yaml", "tracked_eod.yaml"}) {
    const auto robot = rise::sim::load_robot_description(std::string(RISE_SOURCE_DIR) + "/sim/robots/" + file);
    for (const auto& cue : robot.sounds) {
      INFO(file << ": " << cue.sample);
      CHECK(rise::sound::known_sample(cue.sample));
      ++n;
    }
  }
  CHECK(n >= 10);
  CHECK_FALSE(rise::sound::known_sample("no_such_sample"));
}

namespace {
/// sox's RMS level (dB) of [from, from + length) s after the first sound of `input` (sox arguments).
double rms_db(const std::string& input, double from, double length) {
  const std::string cmd = "/usr/bin/sox " + input + " -n silence 1 0.001 -60d trim " + std::to_string(from) + " " +
                          std::to_string(length) + " stats 2>&1";
  FILE* p = ::popen(cmd.c_str(), "r");
  std::string text;
  char buf[512];
  while (p && std::fgets(buf, sizeof buf, p)) text += buf;
  if (p) ::pclose(p);
  INFO(cmd << "\n" << text);
  const auto at = text.find("RMS lev dB");
  REQUIRE(at != std::string::npos);
  return std::stod(text.substr(at + 10));
}

void publish_cue(lcm::LCM& lcm, const std::string& id, const std::string& name, const std::string& sample,
                 bool continuous, float gain) {
  rise_msgs::SoundCue c{};
  c.utime = rise::msgs::wall_us();
  c.robot_id = id;
  c.name = name;
  c.sample = sample;
  c.continuous = continuous;
  c.gain = gain;
  c.pitch = 1.0f;
  c.detail = "test";
  lcm.publish(rise::msgs::sound_channel(id), &c);
}

struct SoundDir {
  fs::path dir;
  SoundDir() {
    char tmpl[] = "/tmp/rise-sound-test-XXXXXX";
    dir = ::mkdtemp(tmpl);
  }
  ~SoundDir() { fs::remove_all(dir); }
  std::string path(const std::string& name) const { return (dir / name).string(); }
};
}  // namespace

TEST_CASE("rise-sound plays SoundCue from LCM through ALSA: the level follows the gain, silence the stop", "[instructor]") {
  if (!fs::exists("/usr/bin/sox")) {
    WARN("skipped: sox is not installed (/usr/bin/sox)");
    return;
  }
  SoundDir d;
  const std::string lcm_url = "udpm://239.255.76.67:" + std::to_string(9400 + ::getpid() % 200) + "?ttl=0";
  const std::string id = "snd" + std::to_string(::getpid());
  // ALSA's file plugin: what ALSA was given, raw 16-bit stereo, beside the program's own --out WAV.
  ChildProcess player({kBin + "/rise-sound", "--id", id, "--lcm", lcm_url, "--device",
                       "file:FILE=" + d.path("alsa.raw") + ",FORMAT=raw", "--out", d.path("mix.wav")},
                      d.path("player.log"));
  REQUIRE(rise::test::wait_for_text(d.path("player.log"), "rise-sound ready"));
  lcm::LCM lcm(lcm_url);
  REQUIRE(lcm.good());
  // As rise-sim sends a continuous cue: every 20 ms; 2 s at 0.2, 2 s at 0.8, 2 s at 0; then a horn.
  const auto t0 = std::chrono::steady_clock::now();
  const auto since = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  bool horned = false;
  while (since() < 7.8) {
    const double t = since();
    if (t < 6.0) publish_cue(lcm, id, "wheel_motors", "wheel_motor_whine", true, t < 2.0 ? 0.2f : t < 4.0 ? 0.8f : 0.0f);
    if (t >= 6.0 && !horned) publish_cue(lcm, id, "horn", "horn", false, 0.8f), horned = true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  player.signal(SIGINT);
  REQUIRE(player.wait_for(5000) == 0);
  const std::string log = rise::test::read_file(d.path("player.log"));
  INFO(log);
  CHECK(log.find(" one-shots)") != std::string::npos);
  const std::string wav = d.path("mix.wav");
  const std::string raw = "-t raw -r 48000 -e signed -b 16 -c 2 " + d.path("alsa.raw");
  for (const auto& input : {wav, raw}) {
    INFO(input);
    // Windows inside each segment (times from the first sound, the first cue).
    const double a = rms_db(input, 0.3, 1.4), b = rms_db(input, 2.3, 1.4), c = rms_db(input, 4.4, 1.2);
    const double horn = rms_db(input, 6.1, 0.4), after = rms_db(input, 7.1, 0.4);
    WARN(input << ": RMS gain 0.2 " << a << " dB, 0.8 " << b << " dB, 0 " << c << " dB, horn " << horn << " dB, after "
               << after << " dB");
    CHECK(b - a == Approx(20.0 * std::log10(4.0)).margin(1.0));  // 12.04 dB: the level follows the gain
    CHECK(a == Approx(20.0 * std::log10(0.2 * 0.4)).margin(1.0));
    CHECK(c < -90.0);  // silent (sox says -inf for zeros)
    CHECK(horn > -20.0);
    CHECK(after < -90.0);
  }
}

TEST_CASE("rise-sound stops after --seconds, and a device ALSA does not know is one line and exit 1", "[instructor]") {
  SoundDir d;
  const std::string lcm_url = "udpm://239.255.76.67:" + std::to_string(9400 + ::getpid() % 200) + "?ttl=0";
  ChildProcess timed({kBin + "/rise-sound", "--id", "quiet", "--lcm", lcm_url, "--device", "null", "--seconds", "0.5",
                      "--out", d.path("quiet.wav")},
                     d.path("timed.log"));
  REQUIRE(timed.wait_for(10000) == 0);
  // 0.5 s at 48 kHz, 16-bit mono, after the 44-byte header.
  CHECK(fs::file_size(d.path("quiet.wav")) == 44 + 24000 * 2);
  ChildProcess bad({kBin + "/rise-sound", "--id", "x", "--lcm", lcm_url, "--device", "no_such_pcm"}, d.path("bad.log"));
  CHECK(bad.wait_for(10000) == 1);
  const std::string log = rise::test::read_file(d.path("bad.log"));
  INFO(log);
  CHECK(log.find("ALSA device 'no_such_pcm'") != std::string::npos);
  CHECK(std::count(log.begin(), log.end(), '\n') == 1);
  ChildProcess version({kBin + "/rise-sound", "--version"}, d.path("version.log"));
  CHECK(version.wait_for(5000) == 0);
  CHECK(rise::test::read_file(d.path("version.log")).rfind("rise-sound ", 0) == 0);
}
