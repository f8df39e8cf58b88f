// One panel, two devices: sticks on CAN, buttons on Modbus TCP. Each board
// lost makes its own controls safe and the panel failsafe; the other keeps
// reporting.

#include <catch2/catch.hpp>

#include "hil/source_factory.hpp"
#include "tests/hil/bridge_test_support.hpp"

using rise::hil::PanelSnapshot;
using namespace rise::hil::test;

TEST_CASE("a panel fed by a CAN board and a Modbus board combines both and fails safe when either is lost",
          "[hil]") {
  const auto def =
      rise::panels::load_panel_definition(std::string(RISE_SOURCE_DIR) + "/panels/definitions/rise_console_split.yaml");
  REQUIRE(def.sources.size() == 2);
  const auto drive_y = *def.find_control("drive_y");
  const auto speed = *def.find_control("speed");

  auto sticks = std::make_unique<EmulatorThread>(def, "mem://split_test", 0);
  auto buttons = std::make_unique<ModbusEmulatorThread>(def, uint16_t{0}, 1);
  sticks->apply(set(def, "drive_y", 0.5f, false));
  buttons->apply(set(def, "deadman", 0.0f, true));
  rise::panels::TimelineEvent fast;
  fast.control = speed;
  fast.position = 2;
  buttons->apply(fast);

  std::vector<std::unique_ptr<rise::hil::SourceTransport>> transports;
  transports.push_back(rise::hil::open_source(def, 0, "mem://split_test"));
  transports.push_back(rise::hil::open_source(def, 1, "modbus+tcp://127.0.0.1:" + std::to_string(buttons->port()) + "?unit=1"));
  Published published;
  rise::hil::Bridge bridge(def, std::move(transports), [&](const PanelSnapshot& s) { published.add(s); });
  bridge.start();

  const auto live = published.wait_for(
      [&](const PanelSnapshot& s) { return !s.failsafe && s.deadman && s.controls[speed].position == 2; }, 5000);
  REQUIRE(live.has_value());
  CHECK(live->controls[drive_y].axis == Approx((0.5 - 0.05) / 0.95).margin(1e-3));
  CHECK(live->sources[0].connected);
  CHECK(live->sources[1].connected);

  SECTION("the Modbus board is lost") {
    const auto before = published.size();
    buttons.reset();
    const auto lost = published.wait_for([](const PanelSnapshot& s) { return s.failsafe; }, 5000, before);
    REQUIRE(lost.has_value());
    CHECK(lost->failsafe_reason.find("buttons:") != std::string::npos);
    CHECK(lost->failsafe_reason.find("sticks:") == std::string::npos);
    CHECK_FALSE(lost->deadman);
    CHECK(lost->controls[drive_y].axis == 0.0f);  // motion stops with the dead-man's board
    CHECK(lost->controls[speed].position == 0);   // safe: slow
    CHECK_FALSE(lost->sources[0].stale);
  }
  SECTION("the CAN board is lost") {
    const auto before = published.size();
    sticks.reset();
    const auto lost = published.wait_for([](const PanelSnapshot& s) { return s.failsafe; }, 5000, before);
    REQUIRE(lost.has_value());
    CHECK(lost->failsafe_reason.find("sticks:") != std::string::npos);
    CHECK(lost->controls[drive_y].axis == 0.0f);
    CHECK(lost->controls[speed].position == 2);  // the healthy board still reports
    CHECK_FALSE(lost->sources[1].stale);
  }
  bridge.stop();
}
