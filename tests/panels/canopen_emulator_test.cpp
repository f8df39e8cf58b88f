// The CANopen node emulator on an in-memory bus, read with the bytes of
// CiA 301: boot-up, heartbeat, NMT, SYNC-triggered and event-driven TPDOs,
// RPDO feedback.

#include <catch2/catch.hpp>

#include <vector>

#include "hil/io/mem_bus.hpp"
#include "panels/canopen_emulator.hpp"

namespace co = rise::firmware_protocol::canopen;
using rise::hil::io::CanFrame;
using rise::hil::io::IoStatus;
using rise::hil::io::MemBus;

namespace {

rise::panels::PanelDefinition console() {
  return rise::panels::load_panel_definition(std::string(RISE_SOURCE_DIR) +
                                             "/panels/definitions/rise_console_canopen.yaml");
}

CanFrame frame(uint32_t id, std::vector<uint8_t> data) {
  CanFrame f;
  f.id = id;
  f.len = static_cast<uint8_t>(data.size());
  std::copy(data.begin(), data.end(), f.data.begin());
  return f;
}

std::vector<CanFrame> drain(MemBus& bus) {
  std::vector<CanFrame> out;
  CanFrame f;
  while (bus.receive(f, 0) == IoStatus::Ok) out.push_back(f);
  return out;
}

std::vector<uint8_t> payload(const CanFrame& f) { return {f.data.begin(), f.data.begin() + f.len}; }

}  // namespace

TEST_CASE("the CANopen emulator boots up, obeys NMT and sends its PDOs as the EDS says", "[panels][canopen]") {
  const auto def = console();
  rise::panels::CanopenEmulator node(def, 0);
  MemBus node_bus("mem://co_emu", "co_emu"), master("mem://co_emu", "co_emu");

  node.tick(node_bus, 0);
  auto frames = drain(master);
  REQUIRE(frames.size() == 1);
  CHECK(frames[0].id == 0x705);
  CHECK(payload(frames[0]) == std::vector<uint8_t>{0x00});  // boot-up
  CHECK(node.state() == co::NmtState::PreOperational);
  node.tick(node_bus, 99'000);
  CHECK(drain(master).empty());
  node.tick(node_bus, 100'000);
  frames = drain(master);
  REQUIRE(frames.size() == 1);
  CHECK(payload(frames[0]) == std::vector<uint8_t>{0x7F});  // heartbeat, pre-operational
  // No PDO before Operational, even on SYNC.
  node.on_frame(node_bus, frame(0x080, {}), 101'000);
  CHECK(drain(master).empty());

  // NMT Start Remote Node: the state is told at once, TPDO2 (event-driven) is sent.
  node.on_frame(node_bus, frame(0x000, {0x01, 0x05}), 102'000);
  CHECK(node.state() == co::NmtState::Operational);
  node.tick(node_bus, 102'000);
  frames = drain(master);
  REQUIRE(frames.size() == 2);
  CHECK(frames[0].id == 0x705);
  CHECK(payload(frames[0]) == std::vector<uint8_t>{0x05});
  CHECK(frames[1].id == 0x285);
  CHECK(payload(frames[1]) == std::vector<uint8_t>{0x00, 0x00});

  SECTION("TPDO1 goes out on each SYNC (transmission type 1), sticks little endian") {
    rise::panels::TimelineEvent e;
    e.control = *def.find_control("drive_y");
    e.axis = 1.0f;
    node.apply(e);
    node.on_frame(node_bus, frame(0x080, {}), 110'000);
    frames = drain(master);
    REQUIRE(frames.size() == 1);
    CHECK(frames[0].id == 0x185);
    // 0x2000:02 = +32767 = 0x7FFF at bytes 2..3.
    CHECK(payload(frames[0]) == std::vector<uint8_t>{0x00, 0x00, 0xFF, 0x7F, 0x00, 0x00, 0x00, 0x00});
    CHECK(node.object_raw(0x2000, 2) == 32767);
  }
  SECTION("TPDO2 goes out on change after its inhibit time, and at its event timer") {
    rise::panels::TimelineEvent press;
    press.control = *def.find_control("estop");
    press.pressed = true;
    node.apply(press);
    node.tick(node_bus, 104'000);  // 2 ms after the last: inside the 5 ms inhibit time
    CHECK(drain(master).empty());
    node.tick(node_bus, 107'000);
    frames = drain(master);
    REQUIRE(frames.size() == 1);
    CHECK(payload(frames[0]) == std::vector<uint8_t>{0x02, 0x00});  // bit 1: e-stop
    node.tick(node_bus, 201'000);
    CHECK(drain(master).empty());
    node.tick(node_bus, 207'000);  // 100 ms event timer
    frames = drain(master);
    REQUIRE(frames.size() == 2);  // the heartbeat (due at 202 ms) too
    CHECK(frames[1].id == 0x285);
  }
  SECTION("an RPDO is shown as LEDs and the display") {
    // b0 power, b1 fault; speed display 0x2101:01 = 142 (1.42 with 2 decimals).
    CHECK(node.on_frame(node_bus, frame(0x205, {0x03, 0x8E, 0x00}), 103'000));
    CHECK(node.feedback("power") == 1.0);
    CHECK(node.feedback("fault") == 1.0);
    CHECK(node.feedback("estop") == 0.0);
    CHECK(node.feedback("speed") == Approx(1.42).margin(1e-9));
    CHECK(node.feedback_text() == "leds power=on fault=on estop=off deadman=off; display speed=1.42");
    CHECK_FALSE(node.on_frame(node_bus, frame(0x205, {0x03, 0x8E, 0x00}), 104'000));
    CHECK_FALSE(node.on_frame(node_bus, frame(0x205, {0x03}), 105'000));  // shorter than its mapping: not taken
  }
  SECTION("reset communication boots the node again; NMT to another node is ignored") {
    node.on_frame(node_bus, frame(0x000, {0x02, 0x06}), 103'000);
    CHECK(node.state() == co::NmtState::Operational);
    node.on_frame(node_bus, frame(0x000, {0x82, 0x00}), 103'000);
    node.tick(node_bus, 104'000);
    frames = drain(master);
    REQUIRE_FALSE(frames.empty());
    CHECK(frames[0].id == 0x705);
    CHECK(payload(frames[0]) == std::vector<uint8_t>{0x00});
    CHECK(node.state() == co::NmtState::PreOperational);
  }
  SECTION("silent: nothing is sent or obeyed until it is powered again") {
    rise::panels::TimelineEvent off;
    off.kind = rise::panels::TimelineEvent::Kind::Silent;
    node.apply(off);
    node.tick(node_bus, 300'000);
    node.on_frame(node_bus, frame(0x080, {}), 300'000);
    CHECK(drain(master).empty());
    off.kind = rise::panels::TimelineEvent::Kind::Resume;
    node.apply(off);
    node.tick(node_bus, 301'000);
    frames = drain(master);
    REQUIRE(frames.size() == 1);
    CHECK(payload(frames[0]) == std::vector<uint8_t>{0x00});
  }
}
