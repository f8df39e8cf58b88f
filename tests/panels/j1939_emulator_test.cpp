// The J1939 console emulator on simulated time: it claims its address
// before it sends, sends each bound message at its GenMsgCycleTime and the
// 20-byte one as a BAM with J1939-21's gaps, and gives its address up to a
// lower NAME.

#include <catch2/catch.hpp>

#include <vector>

#include "firmware_protocol/dbc.hpp"
#include "firmware_protocol/j1939.hpp"
#include "hil/io/mem_bus.hpp"
#include "panels/j1939_emulator.hpp"
#include "panels/panel_definition.hpp"

namespace j = rise::firmware_protocol::j1939;
using rise::panels::J1939Emulator;

namespace {

rise::panels::PanelDefinition definition() {
  return rise::panels::load_panel_definition(std::string(RISE_SOURCE_DIR) +
                                             "/panels/definitions/rise_console_j1939.yaml");
}

struct Sent {
  int64_t at_us;
  j::Frame frame;
};

// Ticks the emulator every millisecond from `from_us` for `ms`, collecting
// what it put on the bus with the simulated time it went out at.
std::vector<Sent> run(J1939Emulator& emulator, rise::hil::io::CanBus& console, rise::hil::io::CanBus& host,
                      int64_t from_us, int ms) {
  std::vector<Sent> sent;
  rise::hil::io::CanFrame f;
  for (int i = 0; i < ms; ++i) {
    const int64_t now = from_us + 1000 * i;
    emulator.tick(console, now);
    while (host.receive(f, 0) == rise::hil::io::IoStatus::Ok) {
      REQUIRE(f.extended);
      j::Frame jf;
      jf.id = j::decode_id(f.id);
      jf.len = f.len;
      std::copy_n(f.data.begin(), f.len, jf.data.begin());
      sent.push_back({now, jf});
    }
  }
  return sent;
}

}  // namespace

TEST_CASE("the J1939 console emulator claims, waits 250 ms, then sends its PGNs and a BAM", "[panels]") {
  const auto def = definition();
  J1939Emulator emulator(def, 0);
  rise::panels::TimelineEvent fast;
  fast.control = *def.find_control("speed");
  fast.position = 2;
  emulator.apply(fast);
  rise::hil::io::MemBus console("mem://j1939_emu", "j1939_emu"), host("mem://j1939_emu", "j1939_emu");
  const auto sent = run(emulator, console, host, 0, 1000);
  REQUIRE_FALSE(sent.empty());
  CHECK(sent[0].frame.id.pgn == j::kPgnAddressClaimed);
  CHECK(sent[0].frame.id.sa == 0x21);
  CHECK(j::name_from_bytes(std::span<const uint8_t, 8>(sent[0].frame.data.data(), 8)) == *def.sources[0].console_name);
  int bjm1 = 0;
  j::TpReceiver rx;
  std::vector<uint8_t> setup;
  int64_t last_dt_us = -1;
  for (const Sent& s : sent) {
    if (s.frame.id.pgn == j::kPgnAddressClaimed) continue;
    CHECK(s.at_us >= 250000);  // nothing before the claim held
    CHECK(s.frame.id.sa == 0x21);
    if (s.frame.id.pgn == 0xFDD6) ++bjm1;
    if (s.frame.id.pgn == j::kPgnTpDt) {
      if (last_dt_us >= 0) CHECK(s.at_us - last_dt_us >= 50000);
      last_dt_us = s.at_us;
    }
    if (auto r = rx.on_frame(s.frame, s.at_us / 1000); r.message && setup.empty())
      setup.assign(r.message->data.begin(), r.message->data.end());
  }
  CHECK(bjm1 >= 35);  // every 20 ms for 750 ms
  CHECK(bjm1 <= 38);
  REQUIRE(setup.size() == 20);
  const auto* message = def.sources[0].dbc->find("CONSOLE_SETUP");
  REQUIRE(message != nullptr);
  CHECK(rise::firmware_protocol::extract_raw(*message->signal("Speed"), setup) == 2);
}

TEST_CASE("the J1939 console emulator gives its address up to a lower NAME and falls silent", "[panels]") {
  const auto def = definition();
  J1939Emulator emulator(def, 0);
  rise::hil::io::MemBus console("mem://j1939_emu2", "j1939_emu2"), host("mem://j1939_emu2", "j1939_emu2");
  run(emulator, console, host, 0, 300);
  REQUIRE(emulator.address() == 0x21);
  j::Frame claim;
  claim.id = {6, j::kPgnAddressClaimed, 0x21, j::kGlobalAddress};
  claim.data = j::name_to_bytes(0x10);  // lower than the console's NAME
  emulator.on_frame(console, [&] {
    rise::hil::io::CanFrame f;
    f.id = j::encode_id(claim.id);
    f.extended = true;
    f.len = 8;
    std::copy_n(claim.data.begin(), 8, f.data.begin());
    return f;
  }(), 300000);
  CHECK(emulator.address() == j::kNullAddress);
  const auto after = run(emulator, console, host, 300000, 200);
  REQUIRE_FALSE(after.empty());
  CHECK(after[0].frame.id.pgn == j::kPgnAddressClaimed);
  CHECK(after[0].frame.id.sa == j::kNullAddress);  // Cannot Claim
  CHECK(after.size() == 1);
}
