// The recorded Modbus session (tests/data/replay/modbus, made by
// make_goldens.sh from the console emulator → rise-hild) replayed through
// the live Bridge by replay:// (ReplayModbusLink) in real time: the
// published PanelStates are the golden's, the end of the trace fails the
// panel safe as a lost slave does, and speed=2 plays in half the time.

#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <mutex>

#include "hil/bridge.hpp"
#include "hil/io/replay_modbus_link.hpp"
#include "hil/modbus_source.hpp"
#include "hil/panel_state_message.hpp"
#include "hil/replay_verify.hpp"
#include "tests/hil/bridge_test_support.hpp"
#include "msgs/clock.hpp"

using namespace rise::hil;

namespace {

const std::string kSession = std::string(RISE_SOURCE_DIR) + "/tests/data/replay/modbus";
const std::string kPanel = std::string(RISE_SOURCE_DIR) + "/panels/definitions/rise_console_modbus.yaml";

// What the bridge published, each with the trace time it played.
struct Played {
  std::mutex mutex;
  std::vector<rise_msgs::PanelState> messages;
  std::vector<int64_t> steady_us;
};

// A live bridge on replay://TRACE?OPTIONS.
struct ReplayRun {
  rise::panels::PanelDefinition def = rise::panels::load_panel_definition(kPanel);
  rise::hil::io::ReplayModbusLink* link = nullptr;
  Played played;
  test::Published published;
  std::unique_ptr<Bridge> bridge;
  int64_t started_us = 0;

  explicit ReplayRun(const std::string& options) {
    auto replay = rise::hil::io::open_modbus_replay("replay://" + kSession + "/console.modbus.log" + options);
    link = replay.get();
    std::vector<std::unique_ptr<rise::hil::SourceTransport>> transports;
    transports.push_back(std::make_unique<rise::hil::ModbusSource>(std::move(replay), def, 0));
    bridge = std::make_unique<Bridge>(def, std::move(transports), [this](const PanelSnapshot& snap) {
      const int64_t t = link->trace_time_us(snap.time_us).value_or(0);
      {
        std::lock_guard lock(played.mutex);
        played.messages.push_back(to_message(def, snap, "replay", static_cast<int64_t>(played.messages.size()), t, {}));
        played.steady_us.push_back(snap.time_us);
      }
      published.add(snap);
    });
    started_us = rise::msgs::monotonic_us();
    bridge->start();
  }
  /// Index of the first published message that is not failsafe (one must have come).
  std::size_t first_healthy() {
    std::lock_guard lock(published.mutex);
    std::size_t i = 0;
    while (i < published.snapshots.size() && published.snapshots[i].failsafe) ++i;
    return i;
  }
};

// The error counters depend on where the daemon's polls fall between the
// recorded ones (a block answered twice is a repeated alive counter): not
// compared here; the offline verifier (replay_verify_test) checks them.
rise_msgs::PanelState without_counters(rise_msgs::PanelState m) {
  for (auto& s : m.sources) s.crc_errors = s.counter_errors = s.length_errors = s.unknown_ids = s.timeouts = s.exceptions = 0;
  return m;
}

}  // namespace

TEST_CASE("a recorded Modbus session replayed through the live bridge by replay:// publishes the golden's "
          "PanelStates and fails safe at its end",
          "[hil]") {
  ReplayRun run("");
  const PanelStateLog golden = read_panel_state_log(kSession + "/panel_state.lcmlog");
  const auto window = run.link->window();
  // The slave's exit is recorded at the end: the panel fails safe as it did
  // (before the first poll it is disconnected too: wait for it to be healthy first).
  REQUIRE(run.published.wait_for([](const PanelSnapshot& s) { return !s.failsafe; }, 5000));
  const auto end = run.published.wait_for(
      [](const PanelSnapshot& s) { return s.failsafe_reason == "console: disconnected"; }, 10000,
      run.first_healthy());
  REQUIRE(end.has_value());
  CHECK(run.published.wait_for([&](const PanelSnapshot& s) { return s.time_us > end->time_us + 200'000; }, 2000));
  run.bridge->stop();
  CHECK(run.link->ended());

  std::lock_guard lock(run.played.mutex);
  const auto& got = run.played.messages;
  REQUIRE(got.size() > 150);
  // The published trace times move on with the wall clock, to the end of the trace.
  CHECK(std::is_sorted(got.begin(), got.end(), [](const auto& a, const auto& b) { return a.utime < b.utime; }));
  CHECK(got.back().utime == window.end_us);

  // Where the golden is steady for ±30 ms (not at an edge that the replay's
  // own poll phase may move by one poll, nor at the golden's own ends), the
  // replayed message nearest in trace time (within two publish periods: a
  // late tick is skipped) must be the golden's.
  VerifySettings loose;
  loose.time_tolerance_us = 30'000;  // ages in a failsafe reason ("for 103 ms")
  std::size_t compared = 0;
  for (const auto& g : golden.messages) {
    bool steady = g.utime - 30'000 >= golden.messages.front().utime && g.utime + 30'000 <= golden.messages.back().utime;
    for (const auto& h : golden.messages)
      if (std::llabs(h.utime - g.utime) <= 30'000 && compare_panel_states(without_counters(g), without_counters(h), loose))
        steady = false;
    if (!steady || g.utime > window.end_us) continue;
    const auto nearest = std::min_element(got.begin(), got.end(), [&](const auto& a, const auto& b) {
      return std::llabs(a.utime - g.utime) < std::llabs(b.utime - g.utime);
    });
    INFO("golden message seq " << g.seq << " at " << (g.utime - window.begin_us) / 1000 << " ms of the trace");
    REQUIRE(std::llabs(nearest->utime - g.utime) <= 20'000);
    const auto difference = compare_panel_states(without_counters(g), without_counters(*nearest), loose);
    INFO((difference ? describe(*difference) : std::string()));
    CHECK_FALSE(difference.has_value());
    ++compared;
  }
  CHECK(compared > golden.messages.size() / 2);

  // What the session holds, at its times (session.txt): driving at 0.5 s,
  // the bad CRCs at 1.2 s, the silence from 1.4 s.
  auto at = [&](double s) {
    const int64_t t = window.begin_us + static_cast<int64_t>(s * 1e6);
    return *std::min_element(got.begin(), got.end(), [&](const auto& a, const auto& b) {
      return std::llabs(a.utime - t) < std::llabs(b.utime - t);
    });
  };
  const auto driving = at(0.5);
  CHECK_FALSE(driving.failsafe);
  CHECK(driving.deadman);
  CHECK(driving.axes[0].value == Approx(-(0.5 - 0.05) / 0.95).margin(1e-3));  // drive_x
  CHECK(driving.axes[1].value == Approx((0.8 - 0.05) / 0.95).margin(1e-3));   // drive_y
  CHECK(std::any_of(got.begin(), got.end(), [&](const auto& m) {
    return m.failsafe_reason == "console: protection check failed" && m.utime > window.begin_us + 1'150'000 &&
           m.utime < window.begin_us + 1'350'000;
  }));
  const auto silent = at(1.58);
  CHECK(silent.failsafe);
  CHECK(silent.failsafe_reason.find("console: stale") == 0);
  CHECK(silent.axes[1].value == 0.0f);
}

TEST_CASE("the end of a Modbus replay fails the panel safe within a poll and a publish period and keeps it so, "
          "and speed=2 plays it in half the time",
          "[hil]") {
  const double speed = GENERATE(1.0, 2.0);
  INFO("speed " << speed);
  // 1.0 s of the session: the console is healthy at its end.
  ReplayRun run("?stop=1.0&speed=" + std::to_string(speed));
  REQUIRE(run.published.wait_for([](const PanelSnapshot& s) { return !s.failsafe; }, 5000));
  const std::size_t from = run.first_healthy();
  const auto end = run.published.wait_for([](const PanelSnapshot& s) { return s.failsafe; }, 5000, from);
  REQUIRE(end.has_value());
  CHECK(end->failsafe_reason == "console: disconnected");
  const double played_s = static_cast<double>(end->time_us - run.started_us) * 1e-6;
  // 1.0 s of trace at `speed`, then at most one poll (10 ms) and one publish period (10 ms) to see it.
  CHECK(played_s >= 1.0 / speed);
  CHECK(played_s <= 1.0 / speed + 0.010 + 0.010 + 0.015);
  // Healthy up to the end: the message before it played the trace's last poll period.
  {
    std::lock_guard lock(run.published.mutex);
    const auto it = std::find_if(run.published.snapshots.begin() + static_cast<std::ptrdiff_t>(from),
                                 run.published.snapshots.end(), [](const PanelSnapshot& s) { return s.failsafe; });
    REQUIRE(it != run.published.snapshots.begin() + static_cast<std::ptrdiff_t>(from));
    const PanelSnapshot& before = *std::prev(it);
    CHECK_FALSE(before.failsafe);
    CHECK(run.link->trace_time_us(before.time_us).value_or(0) >=
          run.link->window().end_us - static_cast<int64_t>(20'000 * speed));
  }
  // It stays lost: reopens fail, as with a slave that is gone.
  const auto later =
      run.published.wait_for([&](const PanelSnapshot& s) { return s.time_us > end->time_us + 400'000; }, 2000);
  REQUIRE(later.has_value());
  CHECK(later->failsafe_reason == "console: disconnected");
  CHECK(run.link->ended());
  CHECK(run.link->counters().reopens == 0);
  CHECK(run.link->writes_dropped() > 0);  // the bridge's LEDs and displays, every feedback period
  run.bridge->stop();
}
