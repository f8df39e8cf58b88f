// A J1939 console (protocol j1939): the shipped definition and its J1939 DBC,
// the console's firmware emulated on an in-memory bus, the bridge's source
// claiming its address, following the console by NAME and reassembling the
// 20-byte CONSOLE_SETUP from its BAM. The kernel's J1939 stack as the peer
// is in tests/vcan (j1939_vm_test).

#include <catch2/catch.hpp>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>

#include "firmware_protocol/j1939.hpp"
#include "hil/io/can_log.hpp"
#include "hil/j1939_source.hpp"
#include "hil/panel_state_message.hpp"
#include "hil/replay_verify.hpp"
#include "hil/session_recorder.hpp"
#include "hil/source_factory.hpp"
#include "msgs/channels.hpp"
#include "panels/j1939_emulator.hpp"
#include "tests/hil/bridge_test_support.hpp"

namespace j1939 = rise::firmware_protocol::j1939;
using rise::hil::PanelMapper;
using rise::hil::PanelSnapshot;
using namespace rise::hil::test;

namespace {

rise::panels::PanelDefinition j1939_console() {
  return rise::panels::load_panel_definition(std::string(RISE_SOURCE_DIR) +
                                             "/panels/definitions/rise_console_j1939.yaml");
}

/// The J1939 console's firmware on a CAN bus, in its own thread.
class J1939ConsoleThread {
 public:
  J1939ConsoleThread(const rise::panels::PanelDefinition& def, const std::string& url, uint8_t address = 254)
      : emulator_(def, 0, settings(address)), bus_(rise::hil::io::open_can_bus(url)) {
    thread_ = std::thread([this] { run(); });
  }
  ~J1939ConsoleThread() {
    running_ = false;
    thread_.join();
  }
  void apply(const rise::panels::TimelineEvent& e) {
    std::lock_guard lock(mutex_);
    emulator_.apply(e);
  }

 private:
  static rise::panels::J1939EmulatorSettings settings(uint8_t address) {
    rise::panels::J1939EmulatorSettings s;
    s.address = address;
    return s;
  }
  void run() {
    rise::hil::io::CanFrame f;
    while (running_) {
      {
        std::lock_guard lock(mutex_);
        emulator_.tick(*bus_, rise::msgs::monotonic_us());
      }
      while (bus_->receive(f, 1) == rise::hil::io::IoStatus::Ok) {
        std::lock_guard lock(mutex_);
        emulator_.on_frame(*bus_, f, rise::msgs::monotonic_us());
      }
    }
  }
  std::mutex mutex_;
  rise::panels::J1939Emulator emulator_;
  std::unique_ptr<rise::hil::io::CanBus> bus_;
  std::atomic<bool> running_{true};
  std::thread thread_;
};

rise::hil::io::CanFrame can(const j1939::Frame& f) {
  rise::hil::io::CanFrame c;
  c.id = j1939::encode_id(f.id);
  c.extended = true;
  c.len = f.len;
  std::copy_n(f.data.begin(), f.len, c.data.begin());
  return c;
}

j1939::Frame claim(uint8_t sa, uint64_t name) {
  j1939::Frame f;
  f.id = {6, j1939::kPgnAddressClaimed, sa, j1939::kGlobalAddress};
  f.data = j1939::name_to_bytes(name);
  return f;
}

/// Waits up to timeout_ms for a frame on `bus` that pred accepts.
template <typename Pred>
std::optional<j1939::Frame> wait_frame(rise::hil::io::CanBus& bus, Pred pred, int timeout_ms) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  rise::hil::io::CanFrame c;
  while (std::chrono::steady_clock::now() < deadline)
    if (bus.receive(c, 10) == rise::hil::io::IoStatus::Ok && c.extended) {
      j1939::Frame f;
      f.id = j1939::decode_id(c.id);
      f.len = c.len;
      std::copy_n(c.data.begin(), c.len, f.data.begin());
      if (pred(f)) return f;
    }
  return std::nullopt;
}

}  // namespace

TEST_CASE("a j1939 source's definition is refused with file:line and the key when it cannot work", "[hil]") {
  const std::string dbc = std::string(RISE_SOURCE_DIR) + "/panels/definitions/rise_console_j1939.dbc";
  const auto text = [&](const std::string& source_extra, const std::string& signal) {
    return "panel: p\n"
           "sources:\n"
           "  - {name: c, protocol: j1939, dbc: " + dbc + source_extra + "}\n"
           "controls:\n"
           "  - {name: x, kind: axis, signal: " + signal + ", safe: 0.0}\n";
  };
  const auto def = rise::panels::parse_panel_definition(text(", console_address: 0x21", "BJM1.DriveX"), "p.yaml");
  CHECK(def.sources[0].is_j1939());
  CHECK(def.sources[0].is_dbc());
  CHECK(def.sources[0].console_address == 0x21);
  CHECK(def.sources[0].j1939_address == 0x80);
  CHECK(def.controls[0].range_min == -100.0);
  CHECK_THROWS_WITH(rise::panels::parse_panel_definition(text("", "BJM1.DriveX"), "p.yaml"),
                    Catch::StartsWith("p.yaml:3: sources[0].console_name: missing"));
  CHECK_THROWS_WITH(rise::panels::parse_panel_definition(text(", console_name: zz", "BJM1.DriveX"), "p.yaml"),
                    Catch::StartsWith("p.yaml:3: sources[0].console_name: expected a 64-bit NAME in hex"));
  CHECK_THROWS_WITH(
      rise::panels::parse_panel_definition(text(", console_address: 0x21, address: 254", "BJM1.DriveX"), "p.yaml"),
      Catch::StartsWith("p.yaml:3: sources[0].address: must be 0..253"));
  CHECK_THROWS_WITH(
      rise::panels::parse_panel_definition(
          "panel: p\nsources:\n  - {name: c, protocol: dbc, dbc: " + dbc + ", address: 3}\ncontrols: []\n", "p.yaml"),
      Catch::StartsWith("p.yaml:3: sources[0].address: only for protocol j1939"));
}

TEST_CASE("a j1939 source matches a message by PGN whatever its priority and addresses", "[hil]") {
  PanelMapper mapper(j1939_console());
  const auto def = j1939_console();
  const std::size_t drive_x = *def.find_control("drive_x");
  mapper.on_connection(0, true, 1);
  // BJM1 (PGN 0xFDD6) as the DBC has it from 0x21 at priority 3, here from
  // 0x95 at priority 6: DriveX = 50.00 % = raw 5000.
  const std::array<uint8_t, 8> bjm1{0x88, 0x13, 0, 0, 0x01, 0, 0, 0};
  const std::array<uint8_t, 8> zeros{};
  const std::array<uint8_t, 20> setup{};
  CHECK(mapper.on_frame(0, j1939::encode_id({6, 0xFDD6, 0x95, 255}), bjm1, 1000, true));
  CHECK(mapper.on_frame(0, j1939::encode_id({6, 0xFDD8, 0x95, 255}), zeros, 1000, true));
  CHECK(mapper.on_frame(0, j1939::encode_id({6, 0xFF10, 0x95, 255}), zeros, 1000, true));
  CHECK(mapper.on_frame(0, j1939::encode_id({6, 0xFF20, 0x95, 255}), setup, 1000, true));
  CHECK_FALSE(mapper.on_frame(0, j1939::encode_id({6, 0xFDD7, 0x95, 255}), bjm1, 1001, true));  // not in the DBC
  CHECK_FALSE(mapper.on_frame(0, 0x0CFDD621, bjm1, 1001, false));  // an 11-bit frame is no J1939 message
  const PanelSnapshot s = mapper.evaluate(2000);
  CHECK_FALSE(s.failsafe);
  CHECK(s.deadman);
  CHECK(s.controls[drive_x].axis == Approx((0.5 - 0.05) / 0.95).margin(1e-3));
}

TEST_CASE("the bridge claims its address, finds the J1939 console by NAME and decodes its BAM message", "[hil]") {
  const auto def = j1939_console();
  const std::size_t drive_y = *def.find_control("drive_y");
  const std::size_t speed = *def.find_control("speed");
  const std::size_t lights = *def.find_control("lights");
  auto console = std::make_unique<J1939ConsoleThread>(def, "mem://j1939_bridge");
  console->apply(set(def, "drive_y", 0.5f, false));
  console->apply(set(def, "deadman", 0.0f, true));
  console->apply(set(def, "lights", 0.0f, true));
  rise::panels::TimelineEvent fast;
  fast.control = speed;
  fast.position = 2;
  console->apply(fast);
  auto peer = rise::hil::io::open_can_bus("mem://j1939_bridge");  // another node on the wire

  std::vector<std::unique_ptr<rise::hil::SourceTransport>> transports;
  transports.push_back(rise::hil::open_source(def, 0, "mem://j1939_bridge"));
  auto* source = dynamic_cast<rise::hil::J1939Source*>(transports.back().get());
  REQUIRE(source != nullptr);
  Published published;
  rise::hil::Bridge bridge(def, std::move(transports), [&](const PanelSnapshot& s) { published.add(s); });
  bridge.start();

  // CONSOLE_SETUP (speed, lights) is 20 bytes: only a reassembled BAM sets them.
  const auto live = published.wait_for(
      [&](const PanelSnapshot& s) { return !s.failsafe && s.deadman && s.controls[speed].position == 2; }, 5000);
  REQUIRE(live.has_value());
  CHECK(live->controls[drive_y].axis == Approx((0.5 - 0.05) / 0.95).margin(1e-3));
  CHECK(live->controls[lights].pressed);
  CHECK(source->own_address() == 0x80);
  CHECK(source->console_address() == 0x21);
  CHECK(source->transport_messages() >= 1);

  SECTION("the console stops: its controls are safe within its timeout and one publish period") {
    const auto before = published.size();
    const auto stopped = std::chrono::steady_clock::now();
    console.reset();
    const auto lost = published.wait_for([](const PanelSnapshot& s) { return s.failsafe; }, 2000, before);
    REQUIRE(lost.has_value());
    const auto took_ms =
        std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - stopped).count();
    CHECK(took_ms <= 100 + 10 + 90);  // timeout_ms + a publish period + this machine's scheduling
    CHECK_FALSE(lost->deadman);
    CHECK(lost->controls[drive_y].axis == 0.0f);
    CHECK(lost->failsafe_reason.find("BJM") != std::string::npos);
  }
  SECTION("the console claims another address with the same NAME: the bridge follows it") {
    // Failsafe after the console stopped (not the one before it first
    // spoke): its last frames no longer count when the moved one is awaited.
    const auto stopped = published.size();
    console.reset();
    REQUIRE(published.wait_for([](const PanelSnapshot& s) { return s.failsafe; }, 2000, stopped).has_value());
    auto moved = std::make_unique<J1939ConsoleThread>(def, "mem://j1939_bridge", 0x95);
    moved->apply(set(def, "deadman", 0.0f, true));
    moved->apply(fast);
    const auto before = published.size();
    const auto back = published.wait_for(
        [&](const PanelSnapshot& s) { return !s.failsafe && s.controls[speed].position == 2; }, 5000, before);
    REQUIRE(back.has_value());
    // Live again, so from the moved console: the source stores its address
    // before that frame's change can be published (J1939Source::receive).
    CHECK(source->console_address() == 0x95);
  }
  SECTION("a lower NAME claims the bridge's address: it claims the next free one and RTS/CTS reaches it there") {
    peer->send(can(claim(0x80, 0x0000000000000001ull)));
    const auto moved =
        wait_frame(*peer, [](const j1939::Frame& f) { return f.id.pgn == j1939::kPgnAddressClaimed && f.id.sa == 0x81; },
                   2000);
    REQUIRE(moved.has_value());
    CHECK(j1939::name_from_bytes(std::span<const uint8_t, 8>(moved->data.data(), 8)) == def.sources[0].j1939_name);
    // A 10-byte PGN 0xFF00 from the console's address to 0x81 (RTS/CTS):
    // the bridge answers CTS then the end-of-message ack.
    j1939::Frame rts;
    rts.id = {7, j1939::kPgnTpCm, 0x21, 0x81};
    rts.data = {16, 10, 0, 2, 0xFF, 0x00, 0xFF, 0x00};
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
    std::optional<j1939::Frame> cts;
    while (!cts && std::chrono::steady_clock::now() < deadline) {  // until the bridge holds 0x81 (250 ms)
      peer->send(can(rts));
      cts = wait_frame(*peer, [](const j1939::Frame& f) { return f.id.pgn == j1939::kPgnTpCm && f.data[0] == 17; }, 100);
    }
    REQUIRE(cts.has_value());
    CHECK(cts->id.sa == 0x81);
    CHECK(cts->id.da == 0x21);
    for (uint8_t seq = 1; seq <= 2; ++seq) {
      j1939::Frame dt;
      dt.id = {7, j1939::kPgnTpDt, 0x21, 0x81};
      dt.data = {seq, 1, 2, 3, 4, 5, 6, 7};
      peer->send(can(dt));
    }
    const auto ack =
        wait_frame(*peer, [](const j1939::Frame& f) { return f.id.pgn == j1939::kPgnTpCm && f.data[0] == 19; }, 1000);
    REQUIRE(ack.has_value());
    CHECK(source->own_address() == 0x81);
  }
  bridge.stop();
}

TEST_CASE("a recorded J1939 session replays through the same claim and reassembly to what was published", "[hil]") {
  const auto def = j1939_console();
  const std::string dir =
      (std::filesystem::temp_directory_path() / ("rise-j1939-session-" + std::to_string(::getpid()))).string();
  std::filesystem::remove_all(dir);
  const std::string channel = rise::msgs::panel_state_channel("rec");
  const std::size_t speed = *def.find_control("speed");
  Published published;
  {
    rise::hil::SessionRecorder recorder(dir);
    std::vector<std::unique_ptr<rise::hil::SourceTransport>> transports;
    transports.push_back(rise::hil::open_source(def, 0, "mem://j1939_session"));
    REQUIRE(recorder.record_source("console", *transports[0], 0));
    J1939ConsoleThread console(def, "mem://j1939_session");
    console.apply(set(def, "deadman", 0.0f, true));
    int64_t seq = 0;
    rise::hil::Bridge bridge(def, std::move(transports), [&](const PanelSnapshot& snap) {
      recorder.record_message(channel, rise::hil::to_message(def, snap, "rec", seq++, rise::msgs::wall_us(), {}));
      published.add(snap);
    });
    bridge.start();
    REQUIRE(published.wait_for([](const PanelSnapshot& s) { return !s.failsafe && s.deadman; }, 5000));
    rise::panels::TimelineEvent fast;
    fast.control = speed;
    fast.position = 2;
    console.apply(fast);  // CONSOLE_SETUP, a BAM
    console.apply(set(def, "drive_y", 0.6f, false));
    REQUIRE(published.wait_for([&](const PanelSnapshot& s) { return s.controls[speed].position == 2; }, 5000));
    REQUIRE(published.wait_for([](const PanelSnapshot&) { return true; }, 5000, published.size() + 20));
    bridge.stop();
  }
  const auto records = rise::hil::io::read_can_log(dir + "/console.log");
  CHECK(std::any_of(records.begin(), records.end(), [](const auto& r) { return r.tx; }));  // our claim and request
  const rise::hil::PanelStateLog golden = rise::hil::read_panel_state_log(dir + "/panel_state.lcmlog");
  REQUIRE(golden.messages.size() == published.size());
  const rise::hil::VerifyReport report =
      rise::hil::verify_replay(def, rise::hil::captures_in(def, dir), golden.messages);
  if (report.difference) INFO(rise::hil::describe(*report.difference));
  CHECK(report.passed());
  std::filesystem::remove_all(dir);
}
