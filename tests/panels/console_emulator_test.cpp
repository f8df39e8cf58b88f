// The console emulator when a looped script starts again: every directive's
// state is undone, as `rise-panel emulate --loop` needs (a script ending in
// @silent used to leave the console silent for good after its first pass).

#include <catch2/catch.hpp>

#include <variant>

#include "firmware_protocol/console_can.hpp"
#include "hil/io/mem_bus.hpp"
#include "panels/console_emulator.hpp"
#include "panels/panel_definition.hpp"
#include "panels/timeline.hpp"

namespace fp = rise::firmware_protocol;
using rise::panels::ConsoleEmulator;

namespace {
const std::string kSource = RISE_SOURCE_DIR;

void play(ConsoleEmulator& emulator, const rise::panels::PanelDefinition& definition, const std::string& script) {
  for (const auto& e : rise::panels::parse_timeline(script, "loop.txt", definition).events) emulator.apply(e);
}

// What one 100 ms stretch of firmware cycles puts on the wire, decoded.
struct Wire {
  int frames = 0;
  int bad = 0;
  std::optional<fp::HeartbeatFrame> heartbeat;
  std::optional<fp::AxesFrame> axes0;
};

Wire run(ConsoleEmulator& emulator, uint8_t node, int64_t& now_us) {
  rise::hil::io::MemBus console("mem://loop", "loop"), host("mem://loop", "loop");
  fp::Decoder decoder(node);
  Wire wire;
  for (int i = 0; i < 100; ++i, now_us += 1000) emulator.tick(console, now_us);
  rise::hil::io::CanFrame f;
  while (host.receive(f, 0) == rise::hil::io::IoStatus::Ok) {
    ++wire.frames;
    const auto r = decoder.decode(f.id, std::span<const uint8_t>(f.data.data(), f.len));
    if (!r.ok()) {
      ++wire.bad;
      continue;
    }
    if (const auto* hb = std::get_if<fp::HeartbeatFrame>(&r.message)) wire.heartbeat = *hb;
    if (const auto* a = std::get_if<fp::AxesFrame>(&r.message); a && a->group == 0) wire.axes0 = *a;
  }
  return wire;
}
}  // namespace

TEST_CASE("a restarted console emulator undoes every directive: silent, corrupt, invalid, status, end",
          "[panels]") {
  const auto definition = rise::panels::load_panel_definition(kSource + "/panels/definitions/rise_console.yaml");
  const uint8_t node = definition.sources.at(0).node;
  ConsoleEmulator emulator(definition, 0);
  int64_t now_us = 1'000'000;

  play(emulator, definition, "0 drive_y 0.8\n0 @invalid drive_x\n0 @status fault\n0 @corrupt 1000\n");
  Wire before = run(emulator, node, now_us);
  REQUIRE(before.frames > 0);
  CHECK(before.bad == before.frames);  // every frame corrupt

  play(emulator, definition, "0 @silent\n");
  CHECK(run(emulator, node, now_us).frames == 0);
  CHECK(emulator.silent());

  emulator.restart();
  CHECK_FALSE(emulator.silent());
  CHECK_FALSE(emulator.ended());
  const Wire after = run(emulator, node, now_us);
  REQUIRE(after.frames > 0);
  CHECK(after.bad == 0);
  REQUIRE(after.heartbeat);
  CHECK(after.heartbeat->status == fp::PanelStatus::Operational);
  REQUIRE(after.axes0);
  CHECK(after.axes0->raw[0] == 0);  // drive_x readable again, at rest
  CHECK(after.axes0->raw[1] == 0);  // drive_y back at rest

  SECTION("an ended script restarts too") {
    play(emulator, definition, "0 @end\n");
    CHECK(emulator.ended());
    emulator.restart();
    CHECK_FALSE(emulator.ended());
    CHECK(run(emulator, node, now_us).frames > 0);
  }
}
