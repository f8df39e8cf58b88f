// A HID source played from a hid-recorder file (replay://): the bridge reads
// it as it reads the device, the session recorder writes it back as
// <source>.hid beside the PanelState log, and the verified replay
// (rise-hild verify) matches the two; the HID golden of tests/data/replay/hid.

#include <catch2/catch.hpp>

#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "hil/bridge.hpp"
#include "hil/io/hid_replay_device.hpp"
#include "hil/replay_verify.hpp"
#include "panels/panel_definition.hpp"
#include "tests/hid_test_devices.hpp"
#include "tests/hil/hid_session_support.hpp"

using namespace rise::hil;
using Clock = std::chrono::steady_clock;

namespace {

const std::string kGolden = std::string(RISE_SOURCE_DIR) + "/tests/data/replay/hid";

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("rise-hidsession-" + std::to_string(::getpid()) + "-" + name))
      .string();
}

const std::vector<uint8_t> gravis(std::begin(rise::test::gravis_descriptor), std::end(rise::test::gravis_descriptor));

rise::hil::io::HidIdentity gravis_identity() {
  rise::hil::io::HidIdentity id;
  id.name = "Gravis GamePad Pro (emulated)";
  id.bus = 3;
  id.vendor_id = 0x0428;
  id.product_id = 0x4001;
  return id;
}

rise::panels::PanelDefinition golden_panel() { return rise::panels::load_panel_definition(kGolden + "/pad.yaml"); }

std::string golden_script() {
  std::ifstream in(kGolden + "/session.txt");
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The golden's input: session.txt on the emulated pad, unplugged 1.65..1.75 s.
int64_t write_golden_input(const std::string& path) {
  rise::hil::test::EmulatedSession session;
  session.unplug_s = 1.65;
  session.plug_s = 1.75;
  return rise::hil::test::write_emulated_session(path, golden_panel(), golden_script(), gravis, gravis_identity(),
                                                 session);
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

TEST_CASE("bridge over a HID replay shows the recorded values at their times, then fails safe at its end", "[hil]") {
  const auto def = rise::panels::parse_panel_definition(
      "panel: gravis\nsources:\n  - {name: pad, protocol: hid, device: 'hid://0428:4001', timeout_ms: 0}\n"
      "controls:\n  - {name: stick_x, kind: axis, signal: x, safe: 0}\n"
      "  - {name: stick_y, kind: axis, signal: y, safe: 0}\n"
      "  - {name: start, kind: button, signal: button_10, safe: false}\n",
      "gravis.yaml");
  const std::string path = temp_path("timed.hid");
  {
    // hid_report.hpp's worked example at 0.2 s, its mirror at 0.4 s, the end at 0.6 s.
    rise::hil::io::HidRecordingWriter w(path, "pad");
    const int64_t t0 = 1'700'000'000'000'000;
    w.plug(t0, gravis, gravis_identity());
    w.report(t0 + 10'000, std::vector<uint8_t>{0x7f, 0x7f, 0x00, 0x00});
    w.report(t0 + 200'000, std::vector<uint8_t>{0x00, 0xff, 0x05, 0x02});
    w.report(t0 + 400'000, std::vector<uint8_t>{0xff, 0x00, 0x00, 0x00});
    w.end(t0 + 600'000);
  }
  auto device = std::make_unique<rise::hil::io::HidReplayDevice>("replay://" + path);
  const auto* replay = device.get();
  std::vector<std::unique_ptr<SourceTransport>> transports;
  transports.push_back(std::make_unique<rise::hil::HidSource>(std::move(device), def, 0));
  struct Stamped {
    double at_ms;
    PanelSnapshot snap;
  };
  std::mutex mutex;
  std::condition_variable published;
  std::vector<Stamped> seen;
  const auto started = Clock::now();
  Bridge bridge(def, std::move(transports), [&](const PanelSnapshot& s) {
    {
      std::lock_guard lock(mutex);
      seen.push_back({std::chrono::duration<double, std::milli>(Clock::now() - started).count(), s});
    }
    published.notify_all();
  });
  bridge.start();
  // The end is published at once (the bridge publishes a loss on change):
  // wait on the published messages for it.
  const auto failsafe_again = [&] {
    return !seen.empty() && seen.back().snap.failsafe && seen.back().snap.failsafe_reason == "pad: disconnected";
  };
  bool ended = false;
  {
    std::unique_lock lock(mutex);
    ended = published.wait_for(lock, std::chrono::seconds(10), [&] { return replay->ended() && failsafe_again(); });
  }
  bridge.stop();
  REQUIRE(replay->ended());
  REQUIRE(ended);
  // When each state first appeared, from the first healthy message (the report at 10 ms).
  auto first = [&](auto pred) {
    for (const auto& s : seen)
      if (pred(s.snap)) return s.at_ms;
    return -1.0;
  };
  const double healthy = first([](const PanelSnapshot& s) { return !s.failsafe; });
  const double worked = first([](const PanelSnapshot& s) { return !s.failsafe && s.controls[2].pressed; });
  const double mirror = first([](const PanelSnapshot& s) { return !s.failsafe && s.controls[0].axis > 0.99f; });
  double end = -1;
  for (const auto& s : seen)
    if (s.at_ms > mirror && s.snap.failsafe) {
      end = s.at_ms;
      break;
    }
  REQUIRE(healthy >= 0);
  REQUIRE(worked >= 0);
  REQUIRE(mirror >= 0);
  REQUIRE(end >= 0);
  WARN("replayed HID states after the first report: " << worked - healthy << " ms (recorded 190), " << mirror - healthy
                                                      << " ms (390), failsafe " << end - healthy
                                                      << " ms (590); max lateness " << replay->max_lateness_us()
                                                      << " us");
  CHECK(worked - healthy == Approx(190.0).margin(8.0));
  CHECK(mirror - healthy == Approx(390.0).margin(8.0));
  CHECK(end - healthy == Approx(590.0).margin(8.0));
  // The decoded values: hid_report.hpp's worked example, then its mirror.
  for (const auto& s : seen) {
    if (s.at_ms < worked || s.at_ms >= mirror) continue;
    CHECK(s.snap.controls[0].axis == Approx(-1.0).margin(1e-6));
    CHECK(s.snap.controls[1].axis == Approx(1.0).margin(1e-6));
    CHECK(s.snap.controls[2].pressed);
  }
  std::lock_guard lock(mutex);
  CHECK(seen.back().snap.controls[0].forced_safe);
  CHECK(seen.back().snap.controls[0].axis == 0.0f);
  std::filesystem::remove(path);
}

TEST_CASE("a HID session recorded from a replayed pad verifies, and a changed report byte fails naming it", "[hil]") {
  const auto def = golden_panel();
  const std::string input = temp_path("input.hid");
  const std::string dir = temp_path("session");
  std::filesystem::remove_all(dir);
  REQUIRE(write_golden_input(input) > 200);
  {
    rise::hil::test::RecordedHidSession session(def, std::make_unique<rise::hil::io::HidReplayDevice>("replay://" + input),
                                                dir);
    // Healthy, then the end of the recording fails it safe for good (after the re-plug).
    REQUIRE(session.published.wait_for([](const PanelSnapshot& s) { return !s.failsafe; }, 5000));
    REQUIRE(session.published.wait_for(
        [](const PanelSnapshot& s) {
          return s.sources[0].reconnects == 1 && s.failsafe && s.failsafe_reason == "pad: disconnected";
        },
        10000));
    session.stop();
    const auto c = session.recorder().counts();
    CHECK(c.hid_reports == session.recording().reports_recorded());
    CHECK(c.hid_reports > 200);
    CHECK(c.lcm_events == session.messages());
    CHECK(c.write_errors == 0);
    CHECK(session.recorder().files() == std::vector<std::string>{dir + "/panel_state.lcmlog", dir + "/pad.hid"});
  }
  // The recording has both plugs, the unplug between them, and its own start.
  rise::hil::io::HidRecordingReader reader(dir + "/pad.hid");
  CHECK(reader.plugs() == 2);
  CHECK(reader.epoch_clock());
  const PanelStateLog golden = read_panel_state_log(dir + "/panel_state.lcmlog");
  const VerifyReport report = verify_replay(def, captures_in(def, dir), golden.messages);
  if (report.difference) INFO(describe(*report.difference));
  CHECK(report.passed());
  CHECK(report.messages == golden.messages.size());
  // Every report, both plugs, the unplug between them and the one at the input's end.
  CHECK(report.records == reader.reports() + 2 + 2);

  SECTION("one report byte changed: the first difference names the control") {
    std::string text = read_text(dir + "/pad.hid");
    REQUIRE(rise::hil::test::undo_first_change(text, 1) > 0);  // byte 1: y
    std::ofstream(dir + "/pad.hid") << text;
    const VerifyReport bad = verify_replay(def, captures_in(def, dir), golden.messages);
    REQUIRE_FALSE(bad.passed());
    INFO(describe(*bad.difference));
    CHECK(bad.difference->field == "drive_y");
    CHECK(std::stod(bad.difference->expected) == Approx(0.8).margin(0.01));
    CHECK(std::stod(bad.difference->got) == Approx(0.0).margin(0.01));
  }
  std::filesystem::remove_all(dir);
  std::filesystem::remove(input);
}

TEST_CASE("the recorded HID session replays to its golden PanelState stream", "[hil]") {
  const auto def = golden_panel();
  const PanelStateLog golden = read_panel_state_log(kGolden + "/panel_state.lcmlog");
  // What the session holds: the dead-man let go, corrupt reports counted,
  // the pad stale while silent, unplugged and plugged in again, then the end.
  auto any = [&](auto pred) { return std::any_of(golden.messages.begin(), golden.messages.end(), pred); };
  CHECK(any([](const rise_msgs::PanelState& m) { return !m.failsafe && !m.deadman; }));
  CHECK(any([](const rise_msgs::PanelState& m) { return m.failsafe_reason.find("pad: stale") == 0; }));
  CHECK(any([](const rise_msgs::PanelState& m) { return m.sources[0].reconnects == 1 && !m.failsafe; }));
  CHECK(golden.messages.back().sources[0].length_errors == 2);
  CHECK(golden.messages.back().failsafe_reason == "pad: disconnected");
  const VerifyReport report = verify_replay(def, captures_in(def, kGolden), golden.messages);
  if (report.difference) INFO(describe(*report.difference));
  CHECK(report.passed());
  CHECK(report.messages == golden.messages.size());

  SECTION("one report byte changed fails at the first message after it") {
    const std::string dir = temp_path("golden-copy");
    std::filesystem::create_directories(dir);
    std::string text = read_text(kGolden + "/pad.hid");
    const int changed = rise::hil::test::undo_first_change(text, 1);  // byte 1: y
    REQUIRE(changed > 0);
    std::ofstream(dir + "/pad.hid") << text;
    const VerifyReport bad = verify_replay(def, captures_in(def, dir), golden.messages);
    REQUIRE_FALSE(bad.passed());
    INFO(describe(*bad.difference));
    CHECK(bad.difference->field == "drive_y");
    // The report's time, from the file: the difference is the first message after it.
    {
      rise::hil::io::HidRecordingReader reader(dir + "/pad.hid");
      rise::hil::io::HidRecordingRecord r;
      int64_t changed_us = -1;
      while (reader.next(r))
        if (r.line == changed) changed_us = r.time_us;
      REQUIRE(changed_us > 0);
      CHECK(bad.difference->utime >= changed_us);
      CHECK(bad.difference->utime - changed_us < 10'000);  // within a publish period
    }
    std::filesystem::remove_all(dir);
  }
}

// make_goldens.sh's first step: RISE_HID_GOLDEN_INPUT=FILE hil_test "[.golden]".
TEST_CASE("the HID golden's input is the emulated pad playing session.txt", "[.golden]") {
  const char* out = std::getenv("RISE_HID_GOLDEN_INPUT");
  REQUIRE(out != nullptr);
  CHECK(write_golden_input(out) > 200);
  rise::hil::io::HidRecordingReader reader(out);
  CHECK(reader.plugs() == 2);
}
