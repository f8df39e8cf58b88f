// The canopen rules of PanelMapper at exact times, with frames in CiA 301's
// bytes: the heartbeat consumer time, the NMT state, PDOs since Operational,
// a cyclic PDO's age, a 29-bit PDO; and the RPDO feedback frames.

#include <catch2/catch.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "hil/feedback.hpp"
#include "hil/panel_mapper.hpp"

using rise::hil::PanelMapper;

namespace {

// A node with a 29-bit event-driven TPDO1 (INTEGER16 stick, BOOLEAN dead-man),
// a TPDO2 every 2nd SYNC (UNSIGNED8 selector) and a 29-bit RPDO1 (BOOLEAN LED,
// INTEGER16 display); heartbeat 100 ms.
const char* const kEds = R"([1017]
ParameterName=Producer heartbeat time
DataType=0x0006
DefaultValue=100
[1800sub1]
ParameterName=COB-ID
DataType=0x0007
DefaultValue=0x20000180+$NODEID
[1800sub2]
ParameterName=Type
DataType=0x0005
DefaultValue=0xFE
[1A00sub0]
ParameterName=Count
DataType=0x0005
DefaultValue=2
[1A00sub1]
ParameterName=Map
DataType=0x0007
DefaultValue=0x20000110
[1A00sub2]
ParameterName=Map
DataType=0x0007
DefaultValue=0x20000201
[1801sub1]
ParameterName=COB-ID
DataType=0x0007
DefaultValue=$NODEID+0x280
[1801sub2]
ParameterName=Type
DataType=0x0005
DefaultValue=2
[1A01sub0]
ParameterName=Count
DataType=0x0005
DefaultValue=1
[1A01sub1]
ParameterName=Map
DataType=0x0007
DefaultValue=0x20010008
[1400sub1]
ParameterName=COB-ID
DataType=0x0007
DefaultValue=0x20000200+$NODEID
[1600sub0]
ParameterName=Count
DataType=0x0005
DefaultValue=2
[1600sub1]
ParameterName=Map
DataType=0x0007
DefaultValue=0x21000101
[1600sub2]
ParameterName=Map
DataType=0x0007
DefaultValue=0x21000210
[2000sub1]
ParameterName=Stick
DataType=0x0003
PDOMapping=1
LowLimit=-1000
HighLimit=1000
[2000sub2]
ParameterName=Hold
DataType=0x0001
PDOMapping=1
[2001]
ParameterName=Selector
DataType=0x0005
PDOMapping=1
[2100sub1]
ParameterName=Lamp
DataType=0x0001
PDOMapping=1
[2100sub2]
ParameterName=Readout
DataType=0x0003
PDOMapping=1
)";

struct Node {
  std::string dir = std::filesystem::temp_directory_path() / ("rise-canopen-" + std::to_string(::getpid()));
  rise::panels::PanelDefinition def;
  Node() {
    std::filesystem::create_directories(dir);
    std::ofstream(dir + "/node.eds") << kEds;
    def = rise::panels::parse_panel_definition(
        "panel: t\n"
        "sources:\n"
        "  - {name: n, protocol: canopen, node: 9, eds: node.eds, sync_ms: 10}\n"
        "controls:\n"
        "  - {name: stick, kind: axis, signal: Stick, motion: true, safe: 0}\n"
        "  - {name: hold, kind: button, signal: '0x2000:02', role: deadman, safe: false}\n"
        "  - {name: sel, kind: switch, signal: Selector, positions: [a, b, c], safe: a}\n"
        "feedback:\n"
        "  leds: [{name: fault, signal: Lamp}]\n"
        "  displays: [{name: speed, signal: '0x2100:02', decimals: 1}]\n",
        dir + "/t.yaml");
  }
  ~Node() { std::filesystem::remove_all(dir); }
};

bool frame(PanelMapper& m, uint32_t id, std::vector<uint8_t> data, int64_t t_ms, bool extended = false) {
  return m.on_frame(0, id, data, t_ms * 1000, extended);
}

}  // namespace

TEST_CASE("a canopen node is trusted only while its heartbeat is fresh and says Operational", "[hil][canopen]") {
  Node n;
  REQUIRE(n.def.sources[0].timeout_ms == 150);
  PanelMapper m(n.def);
  m.on_connection(0, true, 0);
  CHECK(m.evaluate(1000).failsafe_reason == "n: node 9: no heartbeat yet");
  CHECK(frame(m, 0x709, {0x00}, 1));  // boot-up
  CHECK(m.evaluate(2000).failsafe_reason == "n: node 9 boot-up");
  frame(m, 0x709, {0x05}, 10);
  CHECK(m.evaluate(11000).failsafe_reason == "n: node 9: no TPDO1 since operational");
  // TPDO1, 29-bit 0x189: stick -500 (0xFE0C), hold; TPDO2 0x289: selector 2.
  CHECK(frame(m, 0x189, {0x0C, 0xFE, 0x01}, 12, true));
  CHECK(frame(m, 0x289, {0x02}, 13));
  auto s = m.evaluate(14000);
  REQUIRE_FALSE(s.failsafe);
  CHECK(s.controls[0].axis == Approx(-0.5f).margin(1e-4));
  CHECK(s.controls[1].pressed);
  CHECK(s.controls[2].position == 2);
  SECTION("the same id as an 11-bit frame is not the 29-bit TPDO") {
    CHECK_FALSE(frame(m, 0x189, {0x00, 0x00, 0x00}, 15));
    CHECK(m.evaluate(16000).controls[0].axis == Approx(-0.5f).margin(1e-4));
  }
  SECTION("stale one tick after the heartbeat consumer time") {
    frame(m, 0x289, {0x02}, 40);  // the SYNC PDO keeps coming...
    frame(m, 0x289, {0x02}, 60);
    frame(m, 0x289, {0x02}, 80);
    frame(m, 0x289, {0x02}, 100);
    frame(m, 0x289, {0x02}, 120);
    frame(m, 0x289, {0x02}, 140);
    CHECK_FALSE(m.evaluate(160000).failsafe);  // heartbeat 150 ms old
    const auto late = m.evaluate(160001);
    CHECK(late.failsafe_reason == "n: node 9: stale (no heartbeat for 150 ms)");
    CHECK(late.controls[0].forced_safe);
  }
  SECTION("a cyclic TPDO (every 2nd SYNC of 10 ms) is stale after three of its periods") {
    frame(m, 0x709, {0x05}, 60);
    CHECK_FALSE(m.evaluate(73000).failsafe);
    CHECK(m.evaluate(73001).failsafe_reason == "n: node 9: stale (no TPDO2 for 60 ms)");
  }
  SECTION("pre-operational, then Operational again: only PDOs sent since count") {
    frame(m, 0x709, {0x7F}, 20);
    CHECK(m.evaluate(21000).failsafe_reason == "n: node 9 pre-operational");
    frame(m, 0x709, {0x05}, 30);
    CHECK(m.evaluate(31000).failsafe_reason == "n: node 9: no TPDO1 since operational");
    frame(m, 0x189, {0x0C, 0xFE, 0x01}, 32, true);
    frame(m, 0x289, {0x02}, 33);
    CHECK_FALSE(m.evaluate(34000).failsafe);
  }
  SECTION("stopped") {
    frame(m, 0x709, {0x04}, 20);
    CHECK(m.evaluate(21000).failsafe_reason == "n: node 9 stopped");
  }
  SECTION("a lost bus forgets the node") {
    m.on_connection(0, false, 20000);
    m.on_connection(0, true, 21000);
    CHECK(m.evaluate(22000).failsafe_reason == "n: node 9: no heartbeat yet");
  }
}

TEST_CASE("a canopen source's LEDs and displays go out in its 29-bit RPDO", "[hil][canopen]") {
  Node n;
  PanelMapper m(n.def);
  rise::hil::FeedbackRequest request;
  request.displays.push_back({"speed", -1.5f});
  auto snap = m.evaluate(1000);  // failsafe: the fault LED is lit
  auto frames = rise::hil::build_canopen_feedback(n.def, 0, request, snap);
  REQUIRE(frames.size() == 1);
  CHECK(frames[0].cob_id == 0x209);
  CHECK(frames[0].extended);
  REQUIRE(frames[0].len == 3);
  // bit 0 lamp; bits 1..16 readout -15 = 0xFFF1, shifted by one bit.
  CHECK(frames[0].data[0] == static_cast<uint8_t>(0x01 | (0xF1 << 1)));
  CHECK(frames[0].data[1] == static_cast<uint8_t>((0xFFF1 >> 7) & 0xFF));
  CHECK(frames[0].data[2] == static_cast<uint8_t>((0xFFF1 >> 15) & 0x01));
  SECTION("a display beyond its object's range saturates") {
    request.displays[0].second = 99999.0f;
    frames = rise::hil::build_canopen_feedback(n.def, 0, request, snap);
    const unsigned raw = (frames[0].data[0] >> 1) | (frames[0].data[1] << 7) | ((frames[0].data[2] & 1u) << 15);
    CHECK(raw == 0x7FFF);
  }
}
