// A console described only by a DBC file: controls bound to MESSAGE.SIGNAL.
// Real traffic: the 2009 Yaris accelerator-pedal capture with the DBC its
// author used (shared data), read frame by frame and replayed as a device.

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "firmware_protocol/dbc.hpp"
#include "hil/io/can_log.hpp"
#include "tests/hil/bridge_test_support.hpp"

namespace fp = rise::firmware_protocol;
using rise::hil::PanelMapper;
using rise::hil::PanelSnapshot;

namespace {
struct YarisData {
  std::string dbc, log, dir;
  bool present = false;
};

YarisData yaris() {
  YarisData d;
  const char* root = std::getenv("RISE_TEST_DATA");
  if (!root) return d;
  d.dbc = std::string(root) + "/can/opendbc/toyota_iQ_2009_can.dbc";
  d.log = std::string(root) + "/can/CANBUSlogs-yaris09/accellog.log";
  d.present = std::filesystem::exists(d.dbc) && std::filesystem::exists(d.log);
  return d;
}

std::string definition_text(const std::string& dbc) {
  return "panel: yaris-pedal\n"
         "sources:\n"
         "  - {name: car, protocol: dbc, dbc: " + dbc + ", timeout_ms: 200}\n"
         "controls:\n"
         "  - {name: throttle, kind: axis, signal: COMMAND.ACC_PEDAL_SENSOR, range: [0, 255], safe: -1.0}\n"
         "  - {name: pedal_released, kind: button, signal: COMMAND.NOT_ACCELERATING_PEDAL, safe: true}\n";
}
}  // namespace

TEST_CASE("a dbc source's definition names MESSAGE.SIGNAL and is refused with file:line when it does not exist",
          "[hil]") {
  const auto d = yaris();
  if (!d.present) {
    WARN("skipped: the Yaris capture or its DBC is absent under RISE_TEST_DATA");
    return;
  }
  const auto def = rise::panels::parse_panel_definition(definition_text(d.dbc), "y.yaml");
  REQUIRE(def.sources[0].is_dbc());
  REQUIRE(def.controls[0].dbc_signal != nullptr);
  CHECK(def.controls[0].dbc_message->id == 0x2C1);
  std::string bad = definition_text(d.dbc);
  bad.replace(bad.find("ACC_PEDAL_SENSOR"), 16, "ACC_PEDAL_SENSR");
  CHECK_THROWS_WITH(rise::panels::parse_panel_definition(bad, "y.yaml"),
                    Catch::StartsWith("y.yaml:5: controls.throttle.signal: no signal 'COMMAND.ACC_PEDAL_SENSR'"));
  std::string missing = definition_text("/nonexistent/x.dbc");
  CHECK_THROWS_WITH(rise::panels::parse_panel_definition(missing, "y.yaml"),
                    Catch::StartsWith("y.yaml:3: sources[0].dbc: /nonexistent/x.dbc"));
}

TEST_CASE("every pedal frame of a real capture becomes the throttle the DBC says, scaled by its range", "[hil]") {
  const auto d = yaris();
  if (!d.present) {
    WARN("skipped: the Yaris capture or its DBC is absent under RISE_TEST_DATA");
    return;
  }
  PanelMapper mapper(rise::panels::parse_panel_definition(definition_text(d.dbc), "y.yaml"));
  const auto db = fp::DbcDatabase::load(d.dbc);
  const fp::DbcMessage* command = db.find(0x2C1, false);
  REQUIRE(command != nullptr);

  rise::hil::io::CanLogReader reader(d.log);
  rise::hil::io::CanLogRecord r;
  mapper.on_connection(0, true, 1);
  int64_t t0 = -1, last_us = 0;
  int checked = 0;
  double lo = 1e9, hi = -1e9;
  while (reader.next(r)) {
    if (t0 < 0) t0 = r.frame.timestamp_us;
    last_us = 1000 + r.frame.timestamp_us - t0;
    const std::span<const uint8_t> data(r.frame.data.data(), r.frame.len);
    mapper.on_frame(0, r.frame.id, data, last_us, r.frame.extended);
    if (r.frame.id != 0x2C1) continue;
    const auto s = mapper.evaluate(last_us);
    INFO(s.failsafe_reason);
    REQUIRE_FALSE(s.failsafe);
    // The oracle: the DBC's own decode of this frame.
    double pedal = 0, released = 0;
    for (const auto& sig : db.decode(*command, data)) {
      if (sig.signal->name == "ACC_PEDAL_SENSOR") pedal = sig.value;
      if (sig.signal->name == "NOT_ACCELERATING_PEDAL") released = sig.value;
    }
    CHECK(s.controls[0].axis == Approx(std::clamp(2.0 * pedal / 255.0 - 1.0, -1.0, 1.0)).margin(1e-5));
    CHECK(s.controls[1].pressed == (released != 0.0));
    lo = std::min(lo, pedal);
    hi = std::max(hi, pedal);
    ++checked;
  }
  CHECK(checked == 228);  // COMMAND frames in accellog.log
  CHECK(hi - lo > 50);    // the pedal really moved
  const auto snap = mapper.evaluate(last_us);
  CHECK(snap.sources[0].errors[static_cast<std::size_t>(fp::DecodeError::UnknownId)] > 0);  // other ECUs' frames
  // The capture ends: after the source timeout the pedal is at its safe value.
  const auto stale = mapper.evaluate(last_us + 200'001);
  CHECK(stale.failsafe);
  CHECK(stale.controls[0].axis == -1.0f);
  CHECK(stale.failsafe_reason.find("no COMMAND frame for") != std::string::npos);
}

TEST_CASE("the bridge reads a replayed capture as if it were the car, and re-opens it when it ends like a device "
          "that returns",
          "[hil]") {
  const auto d = yaris();
  if (!d.present) {
    WARN("skipped: the Yaris capture or its DBC is absent under RISE_TEST_DATA");
    return;
  }
  const auto def = rise::panels::parse_panel_definition(definition_text(d.dbc), "y.yaml");
  std::vector<std::unique_ptr<rise::hil::io::CanBus>> buses;
  buses.push_back(rise::hil::io::open_can_bus("replay://" + d.log + "?speed=8"));  // 7.2 s of traffic in 0.9 s
  rise::hil::test::Published published;
  rise::hil::Bridge bridge(def, std::move(buses), [&](const PanelSnapshot& s) { published.add(s); });
  bridge.start();
  const auto live = published.wait_for([](const PanelSnapshot& s) { return !s.failsafe; }, 5000);
  REQUIRE(live.has_value());
  CHECK(live->controls[0].axis > -1.0f);
  // At its end the replay reports the device gone; the bridge re-opens it
  // (from the start), as it does for a device that comes back.
  const auto again = published.wait_for(
      [](const PanelSnapshot& s) { return !s.failsafe && s.sources[0].reconnects >= 1; }, 10000);
  REQUIRE(again.has_value());
  bridge.stop();
  // Throttle values moved while the capture played.
  std::lock_guard lock(published.mutex);
  float lo = 1, hi = -1;
  for (const auto& s : published.snapshots)
    if (!s.failsafe) {
      lo = std::min(lo, s.controls[0].axis);
      hi = std::max(hi, s.controls[0].axis);
    }
  CHECK(hi - lo > 0.3f);
}
