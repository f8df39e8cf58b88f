// The bridge's Modbus source against the console emulator serving the
// rise-modbus-v1 map over real TCP on 127.0.0.1 (ModbusServer, libmodbus).

#include <catch2/catch.hpp>

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <condition_variable>
#include <fstream>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>

#include "hil/bridge.hpp"
#include "hil/io/modbus_server.hpp"
#include "hil/source_factory.hpp"
#include "msgs/failsafe.hpp"
#include "panels/console_emulator.hpp"
#include "tests/hil/bridge_test_support.hpp"
#include "tests/socat_ptys.hpp"

namespace fp = rise::firmware_protocol;
using rise::hil::PanelSnapshot;
using rise::hil::test::Published;
using rise::hil::test::set;
using rise::hil::test::ModbusEmulatorThread;
using rise::test::SocatPtys;

namespace {

// The reference console on rise-modbus-v1 (panels/definitions), with the
// source timeout a test wants.
rise::panels::PanelDefinition modbus_console(int timeout_ms = 100) {
  std::ifstream in(std::string(RISE_SOURCE_DIR) + "/panels/definitions/rise_console_modbus.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  const std::string timeout = "timeout_ms: 100";
  yaml.replace(yaml.find(timeout), timeout.size(), "timeout_ms: " + std::to_string(timeout_ms));
  return rise::panels::parse_panel_definition(yaml, "rise_console_modbus.yaml");
}



rise::panels::TimelineEvent directive(rise::panels::TimelineEvent::Kind kind, int count = 0) {
  rise::panels::TimelineEvent e;
  e.kind = kind;
  e.count = count;
  return e;
}


std::vector<std::unique_ptr<rise::hil::SourceTransport>> modbus_transport(const rise::panels::PanelDefinition& def,
                                                                          const std::string& url) {
  std::vector<std::unique_ptr<rise::hil::SourceTransport>> t;
  t.push_back(rise::hil::open_source(def, 0, url));
  return t;
}

std::vector<std::unique_ptr<rise::hil::SourceTransport>> modbus_transport(const rise::panels::PanelDefinition& def,
                                                                          uint16_t port) {
  return modbus_transport(def, "modbus+tcp://127.0.0.1:" + std::to_string(port) + "?unit=1&timeout_ms=50");
}

}  // namespace

TEST_CASE("the bridge polls a Modbus console, writes its feedback, fails safe when the console is killed "
          "and recovers when it returns",
          "[hil]") {
  const auto def = modbus_console();
  const auto drive_y = *def.find_control("drive_y");
  auto emulator = std::make_unique<ModbusEmulatorThread>(def, 0);
  const uint16_t port = emulator->port();
  emulator->apply(set(def, "deadman", 0, true));
  emulator->apply(set(def, "drive_y", 0.6f, false));

  Published published;
  rise::hil::Bridge bridge(def, modbus_transport(def, port), [&](const PanelSnapshot& s) { published.add(s); });
  bridge.start();

  const auto live = published.wait_for(
      [&](const PanelSnapshot& s) { return !s.failsafe && s.deadman && s.controls[drive_y].axis > 0.5f; }, 3000);
  REQUIRE(live.has_value());
  CHECK(live->controls[drive_y].axis == Approx((0.6 - 0.05) / 0.95).margin(1e-3));
  CHECK(live->sources[0].frames_ok > 0);

  rise::hil::FeedbackRequest request;
  request.displays.emplace_back("speed", 1.25f);
  request.buzzer = fp::BuzzerMode::Beep;
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
  CHECK(fb.displays.at(0).decimals == 2);
  CHECK(fb.buzzer == fp::BuzzerMode::Beep);
  CHECK(fb.bad_frames == 0);

  // Kill the peer: its server closes the connections.
  const std::size_t before = published.size();
  emulator.reset();
  const auto lost = published.wait_for([](const PanelSnapshot& s) { return s.failsafe; }, 3000, before);
  REQUIRE(lost.has_value());
  CHECK(lost->controls[drive_y].axis == 0.0f);
  const int64_t timeout_us = 1000 * def.sources[0].timeout_ms;
  CHECK(lost->sources[0].last_frame_age_us <= timeout_us + def.publish_period_us() + 15000);
  {
    std::lock_guard lock(published.mutex);
    for (const auto& s : published.snapshots)
      if (s.sources[0].last_frame_age_us > timeout_us) CHECK(s.failsafe);
  }

  // The console comes back on the same port: the bridge reconnects (back-off ≤ 2 s).
  emulator = std::make_unique<ModbusEmulatorThread>(def, port);
  emulator->apply(set(def, "deadman", 0, true));
  emulator->apply(set(def, "drive_y", -0.6f, false));
  const std::size_t lost_at = published.size();
  const auto back = published.wait_for(
      [&](const PanelSnapshot& s) { return !s.failsafe && s.controls[drive_y].axis < -0.5f; }, 5000, lost_at);
  REQUIRE(back.has_value());
  CHECK(back->sources[0].reconnects >= 1);
  bridge.stop();
}

TEST_CASE("a Modbus console whose registers freeze goes stale after timeout_ms, and a torn block fails the "
          "protection check",
          "[hil]") {
  const auto def = modbus_console(100);
  ModbusEmulatorThread emulator(def, 0);
  emulator.apply(set(def, "deadman", 0, true));
  Published published;
  rise::hil::Bridge bridge(def, modbus_transport(def, emulator.port()), [&](const PanelSnapshot& s) { published.add(s); });
  bridge.start();
  REQUIRE(published.wait_for([](const PanelSnapshot& s) { return !s.failsafe; }, 3000).has_value());

  SECTION("frozen firmware: registers still served, alive counter stopped") {
    const std::size_t from = published.size();
    emulator.apply(directive(rise::panels::TimelineEvent::Kind::Silent));
    const auto stale = published.wait_for([](const PanelSnapshot& s) { return s.failsafe; }, 3000, from);
    REQUIRE(stale.has_value());
    CHECK(rise::msgs::has(stale->failsafe_causes, rise::msgs::FailsafeCause::SourceStale));
    CHECK(stale->sources[0].connected);
    CHECK(stale->sources[0].last_frame_age_us <= 1000 * def.sources[0].timeout_ms + def.publish_period_us() + 15000);
    CHECK(bridge.snapshot().sources[0].errors[static_cast<std::size_t>(fp::DecodeError::RepeatedCounter)] > 0);
  }
  SECTION("a bad map CRC") {
    const std::size_t from = published.size();
    emulator.apply(directive(rise::panels::TimelineEvent::Kind::Corrupt, 3));
    const auto failed = published.wait_for(
        [](const PanelSnapshot& s) { return rise::msgs::has(s.failsafe_causes, rise::msgs::FailsafeCause::ProtectionFailed); }, 3000,
        from);
    REQUIRE(failed.has_value());
    CHECK(failed->sources[0].errors[static_cast<std::size_t>(fp::DecodeError::BadCrc)] >= 1);
    // recovery_frames good blocks later it is trusted again
    const std::size_t after = published.size();
    CHECK(published.wait_for([](const PanelSnapshot& s) { return !s.failsafe; }, 3000, after).has_value());
  }
  bridge.stop();
}

TEST_CASE("the bridge polls a Modbus RTU console across a socat pty pair, fails safe when socat dies and "
          "recovers when it returns",
          "[hil]") {
  if (!rise::test::have_socat()) {
    WARN("socat not installed: RTU bridge test skipped");
    return;
  }
  const auto def = modbus_console(100);
  const auto drive_y = *def.find_control("drive_y");
  const std::string dir = std::filesystem::temp_directory_path() / ("rise-rtu-bridge-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string console_end = dir + "/console", host_end = dir + "/host";
  auto socat = std::make_unique<SocatPtys>(console_end, host_end, dir + "/socat.log");
  REQUIRE(socat->ready());

  ModbusEmulatorThread emulator(def, "modbus+rtu-listen://" + console_end + "?baud=115200&unit=3");
  emulator.apply(set(def, "deadman", 0, true));
  emulator.apply(set(def, "drive_y", 0.6f, false));
  Published published;
  rise::hil::Bridge bridge(def, modbus_transport(def, "modbus+rtu://" + host_end + "?baud=115200&unit=3&timeout_ms=50"),
                           [&](const PanelSnapshot& s) { published.add(s); });
  bridge.start();
  REQUIRE(published.wait_for([&](const PanelSnapshot& s) { return !s.failsafe && s.controls[drive_y].axis > 0.5f; },
                             3000)
              .has_value());

  const std::size_t before = published.size();
  socat->crash();  // no goodbye on the ptys
  const auto lost = published.wait_for([](const PanelSnapshot& s) { return s.failsafe; }, 3000, before);
  REQUIRE(lost.has_value());
  CHECK(lost->controls[drive_y].axis == 0.0f);
  CHECK(lost->sources[0].last_frame_age_us <= 1000 * def.sources[0].timeout_ms + def.publish_period_us() + 15000);

  const std::size_t lost_at = published.size();
  socat = std::make_unique<SocatPtys>(console_end, host_end, dir + "/socat.log");
  REQUIRE(socat->ready());
  const auto back = published.wait_for([](const PanelSnapshot& s) { return !s.failsafe; }, 8000, lost_at);
  REQUIRE(back.has_value());
  CHECK(back->sources[0].reconnects >= 1);
  bridge.stop();
  std::filesystem::remove_all(dir);
}
