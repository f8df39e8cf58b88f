// The session recorder (rise-hild --record) in front of a live bridge: what
// it writes replays to what the bridge published, and a full disk costs
// records, not the session.

#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>

#include "hil/io/can_log.hpp"
#include "hil/panel_state_message.hpp"
#include "hil/replay_verify.hpp"
#include "hil/session_recorder.hpp"
#include "hil/source_factory.hpp"
#include "msgs/channels.hpp"
#include "msgs/clock.hpp"
#include "tests/hil/bridge_test_support.hpp"

using namespace rise::hil;
using rise::hil::test::console;
using rise::hil::test::EmulatorThread;
using rise::hil::test::Published;
using rise::hil::test::set;

namespace {
std::string temp_dir(const std::string& name) {
  return std::filesystem::temp_directory_path() / (name + "-" + std::to_string(::getpid()));
}

}  // namespace

TEST_CASE("a session recorded from a live bridge replays to the PanelState stream it published", "[hil]") {
  const auto def = console();
  const std::string dir = temp_dir("rise-session");
  std::filesystem::remove_all(dir);
  const std::string channel = rise::msgs::panel_state_channel("rec");
  Published published;
  std::size_t frames_seen = 0;
  {
    SessionRecorder recorder(dir);
    std::vector<std::unique_ptr<SourceTransport>> transports;
    transports.push_back(rise::hil::open_source(def, 0, "mem://session_recorder_test"));
    REQUIRE(recorder.record_source("console", *transports[0], 0));
    EmulatorThread emulator(def, "mem://session_recorder_test");
    int64_t seq = 0;
    Bridge bridge(def, std::move(transports), [&](const PanelSnapshot& snap) {
      recorder.record_message(channel, to_message(def, snap, "rec", seq++, rise::msgs::wall_us(), {}));
      published.add(snap);
    });
    bridge.start();
    REQUIRE(published.wait_for([](const PanelSnapshot& s) { return !s.failsafe; }, 5000));
    emulator.apply(set(def, "deadman", 0, true));
    emulator.apply(set(def, "drive_y", 0.6f, false));
    REQUIRE(published.wait_for([](const PanelSnapshot& s) { return s.deadman && s.controls[1].axis > 0.5f; }, 5000));
    emulator.apply(set(def, "deadman", 0, false));
    REQUIRE(published.wait_for([](const PanelSnapshot& s) { return !s.failsafe && !s.deadman && s.controls[1].axis == 0.0f; }, 5000, published.size()));
    // A few periodic messages more, with the console's cyclic frames between them.
    REQUIRE(published.wait_for([](const PanelSnapshot&) { return true; }, 5000, published.size() + 20));
    bridge.stop();
    const auto c = recorder.counts();
    CHECK(c.lcm_events == seq);
    CHECK(c.can_frames > 20);
    CHECK(c.write_errors == 0);
    frames_seen = static_cast<std::size_t>(c.can_frames);
    CHECK(recorder.files() == std::vector<std::string>{dir + "/panel_state.lcmlog", dir + "/console.log"});
  }
  // Both directions are in the candump log: the console's frames and the bridge's feedback.
  const auto records = rise::hil::io::read_can_log(dir + "/console.log");
  CHECK(records.size() == frames_seen);
  CHECK(std::any_of(records.begin(), records.end(), [](const auto& r) { return r.tx; }));
  CHECK(std::any_of(records.begin(), records.end(), [](const auto& r) { return !r.tx; }));

  const PanelStateLog golden = read_panel_state_log(dir + "/panel_state.lcmlog");
  CHECK(golden.channel == channel);
  CHECK(golden.messages.size() == published.size());
  const VerifyReport report = verify_replay(def, captures_in(def, dir), golden.messages);
  if (report.difference) INFO(describe(*report.difference));
  CHECK(report.passed());
  CHECK(report.messages == golden.messages.size());
  std::filesystem::remove_all(dir);
}

TEST_CASE("a session recorder on a full disk counts the lost PanelState events and goes on", "[hil]") {
  const std::string dir = temp_dir("rise-session-full");
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::filesystem::create_symlink("/dev/full", dir + "/panel_state.lcmlog");
  SessionRecorder recorder(dir);
  const auto def = console();
  const PanelMapper mapper(def);
  const auto message = to_message(def, mapper.preview(1), "full", 0, rise::msgs::wall_us(), {});
  // Events are flushed every 100 ms; the first flush onto /dev/full fails.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (recorder.counts().write_errors == 0 && std::chrono::steady_clock::now() < deadline)
    recorder.record_message("rise/full/panel_state", message);
  CHECK(recorder.counts().write_errors > 0);
  std::filesystem::remove_all(dir);
}
