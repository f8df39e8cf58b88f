#include <catch2/catch.hpp>

#include <atomic>
#include <mutex>
#include <thread>

#include "msgs/failsafe.hpp"
#include "tests/hil/bridge_test_support.hpp"

namespace fp = rise::firmware_protocol;
using rise::hil::PanelSnapshot;
using namespace rise::hil::test;

namespace {

}  // namespace

TEST_CASE("the bridge publishes the emulated console's state, sends feedback, and goes failsafe within one "
          "publish period of the source timeout",
          "[hil]") {
  const auto def = console();
  const auto drive_y = *def.find_control("drive_y");
  Published published;
  std::vector<std::unique_ptr<rise::hil::io::CanBus>> buses;
  buses.push_back(rise::hil::io::open_can_bus("mem://bridge_test"));
  rise::hil::Bridge bridge(def, std::move(buses), [&](const PanelSnapshot& s) { published.add(s); });
  bridge.start();

  auto emulator = std::make_unique<EmulatorThread>(def, "mem://bridge_test");
  emulator->apply(set(def, "deadman", 0, true));
  emulator->apply(set(def, "drive_y", 0.6f, false));

  const auto live = published.wait_for(
      [&](const PanelSnapshot& s) { return !s.failsafe && s.deadman && s.controls[drive_y].axis > 0.5f; }, 3000);
  REQUIRE(live.has_value());
  CHECK(live->controls[drive_y].axis == Approx((0.6 - 0.05) / 0.95).margin(1e-3));

  // The console shows what the bridge sends back: power LED on, no fault.
  rise::hil::FeedbackRequest request;
  request.displays.emplace_back("speed", 1.25f);
  bridge.set_feedback(request);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(3);
  while (std::chrono::steady_clock::now() < deadline) {
    const auto fb = emulator->feedback();
    if (fb.displays.count(0) && fb.displays.at(0).raw == 125 && (fb.leds_on & 1u)) break;
    std::this_thread::yield();
  }
  const auto fb = emulator->feedback();
  CHECK((fb.leds_on & 0b111u) == 0b001u);
  REQUIRE(fb.displays.count(0) == 1);
  CHECK(fb.displays.at(0).raw == 125);
  CHECK(fb.bad_frames == 0);

  // Pull the plug: the emulator's thread ends, no more frames arrive.
  const std::size_t before = published.size();
  emulator.reset();
  const auto lost = published.wait_for([](const PanelSnapshot& s) { return s.failsafe; }, 3000, before);
  REQUIRE(lost.has_value());
  const int64_t timeout_us = 1000 * def.sources[0].timeout_ms;
  const int64_t period_us = def.publish_period_us();
  CHECK(rise::msgs::has(lost->failsafe_causes, rise::msgs::FailsafeCause::SourceStale));
  CHECK(lost->controls[drive_y].axis == 0.0f);
  // Exact property: no snapshot older than the timeout was ever published as safe.
  {
    std::lock_guard lock(published.mutex);
    for (const auto& s : published.snapshots)
      if (s.sources[0].last_frame_age_us > timeout_us) CHECK(s.failsafe);
  }
  // And the failsafe snapshot came within one publish period of the timeout
  // (plus scheduling slack of this 2-core machine).
  CHECK(lost->sources[0].last_frame_age_us <= timeout_us + period_us + 15000);
  bridge.stop();
}
