// protocol: canopen against a real Linux CAN stack (the VM of
// run_in_vcan_vm.sh: vcan0, can-utils' cansend and candump in PATH). The
// bridge runs on socketcan://vcan0 against two peers that are not itself:
// rise-panel emulate as a CANopen node in its own process, and frames typed
// into cansend with the bytes of CiA 301 (boot-up 705#00, heartbeats 705#05
// and 705#7F, TPDOs); candump shows the bridge's NMT and SYNC frames.

#include <catch2/catch.hpp>

#include <sys/stat.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "hil/bridge.hpp"
#include "hil/source_factory.hpp"
#include "tests/hil/bridge_test_support.hpp"
#include "tests/vcan/vm_children.hpp"

using rise::hil::PanelSnapshot;
using rise::test::vm::Child;
using rise::test::vm::Pipe;
using rise::test::vm::read_available;
using rise::test::vm::run;

namespace {

constexpr int kPeerTimeoutMs = 10000;  // generous: the guest is emulated (TCG)
const std::string kDefinitions = std::string(RISE_SOURCE_DIR) + "/panels/definitions";

void require_vm() {
  struct stat st {};
  if (::stat("/sys/class/net/vcan0", &st) != 0) FAIL("no vcan0: run this program with tests/vcan/run_in_vcan_vm.sh");
}

// candump -L on vcan0 with `filters`, its output collected until `wanted`
// are all in it or the deadline passes.
class Candump {
 public:
  explicit Candump(const std::string& filters) : child_({"candump", "-L", "vcan0," + filters}, out_.write_fd) {
    REQUIRE(child_.started());
    out_.close_write();
    // Bound once it runs: an id:mask filter of 0x7FF lands in the kernel's single-id list.
    REQUIRE(rise::test::vm::wait_for_can_receiver("vcan0", {"sff", "fil"}, kPeerTimeoutMs));
  }
  bool saw_all(const std::vector<std::string>& wanted, int timeout_ms) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (true) {
      text_ += read_available(out_.read_fd, 50);
      bool all = true;
      for (const auto& w : wanted) all = all && text_.find(w) != std::string::npos;
      if (all) return true;
      if (std::chrono::steady_clock::now() > deadline) return false;
    }
  }
  const std::string& text() const { return text_; }

 private:
  Pipe out_;
  Child child_;
  std::string text_;
};

std::unique_ptr<rise::hil::Bridge> start_bridge(const rise::panels::PanelDefinition& def,
                                                rise::hil::test::Published& published) {
  std::vector<std::unique_ptr<rise::hil::SourceTransport>> transports;
  transports.push_back(rise::hil::open_source(def, 0, "socketcan://vcan0"));
  auto bridge = std::make_unique<rise::hil::Bridge>(def, std::move(transports),
                                                    [&](const PanelSnapshot& s) { published.add(s); });
  bridge->start();
  return bridge;
}

}  // namespace

TEST_CASE("the bridge resets and starts rise-panel's CANopen node on vcan0, and candump sees NMT and SYNC",
          "[vcan][canopen]") {
  require_vm();
  Candump candump("000:7FF,080:7FF");
  const auto def = rise::panels::load_panel_definition(kDefinitions + "/rise_console_canopen.yaml");
  Child node({RISE_PANEL_BIN, "emulate", "--panel", kDefinitions + "/rise_console_canopen.yaml", "--can",
              "socketcan://vcan0"});
  REQUIRE(node.started());
  rise::hil::test::Published published;
  auto bridge = start_bridge(def, published);
  const auto ok = published.wait_for([](const PanelSnapshot& s) { return !s.failsafe; }, 3 * kPeerTimeoutMs);
  INFO("last reason: " << bridge->snapshot().failsafe_reason);
  REQUIRE(ok);
  // CiA 301: NMT Reset Communication of node 5, NMT Start Remote Node, SYNC without data.
  CHECK(candump.saw_all({"vcan0 000#8205", "vcan0 000#0105", "vcan0 080#\n"}, kPeerTimeoutMs));
  INFO("candump printed:\n" << candump.text());
  CHECK(candump.text().find("080#") != std::string::npos);
  bridge->stop();
}

TEST_CASE("frames typed into cansend drive the bridge: boot-up, heartbeat 05 and 7F, TPDOs, silence",
          "[vcan][canopen]") {
  require_vm();
  // The shipped EDS with SYNC every second and a 3 s heartbeat consumer
  // time, so that cansend (a process per frame, under TCG) keeps up.
  const auto def = rise::panels::parse_panel_definition(
      "panel: co-raw\n"
      "sources:\n"
      "  - {name: console, protocol: canopen, node: 5, eds: " + kDefinitions + "/rise_console_canopen.eds,"
      " timeout_ms: 3000, sync_ms: 1000}\n"
      "controls:\n"
      "  - {name: drive_x, kind: axis, signal: Left stick X, motion: true, safe: 0}\n"
      "  - {name: deadman, kind: button, signal: '0x2001:01', role: deadman, safe: false}\n"
      "  - {name: estop, kind: button, signal: E-stop, role: estop, safe: true}\n",
      "/tmp/co_raw.yaml");
  Candump candump("000:7FF,080:7FF");
  rise::hil::test::Published published;
  auto bridge = start_bridge(def, published);
  const std::size_t drive_x = *def.find_control("drive_x");

  // Boot-up (CiA 301 §7.2.8.3.3: the heartbeat COB-ID, one byte 0).
  REQUIRE(run({"cansend", "vcan0", "705#00"}) == 0);
  REQUIRE(candump.saw_all({"vcan0 000#0105"}, kPeerTimeoutMs));
  // Operational; TPDO1 Left stick X = 0x4000 (+16384, INTEGER16 little endian);
  // TPDO2 bit 0 dead-man held, bit 1 e-stop released.
  REQUIRE(run({"cansend", "vcan0", "705#05"}) == 0);
  REQUIRE(run({"cansend", "vcan0", "185#0040000000000000"}) == 0);
  REQUIRE(run({"cansend", "vcan0", "285#0100"}) == 0);
  const auto live = published.wait_for(
      [&](const PanelSnapshot& s) {
        return !s.failsafe && s.deadman && s.controls[drive_x].axis == Approx(16384.0 / 32767.0).margin(1e-3);
      },
      kPeerTimeoutMs);
  INFO("last reason: " << bridge->snapshot().failsafe_reason);
  REQUIRE(live);
  CHECK(candump.saw_all({"vcan0 080#\n"}, kPeerTimeoutMs));

  // Pre-operational: failsafe as soon as the heartbeat is read.
  std::size_t from = published.size();
  REQUIRE(run({"cansend", "vcan0", "705#7F"}) == 0);
  const auto preop = published.wait_for([](const PanelSnapshot& s) { return s.failsafe; }, kPeerTimeoutMs, from);
  REQUIRE(preop);
  CHECK(preop->failsafe_reason == "console: node 5 pre-operational");
  CHECK(preop->controls[drive_x].forced_safe);
  CHECK(preop->controls[drive_x].axis == 0.0f);

  // Operational again: the TPDOs sent before do not count, fresh ones do.
  REQUIRE(run({"cansend", "vcan0", "705#05"}) == 0);
  from = published.size();
  REQUIRE(run({"cansend", "vcan0", "185#00C0000000000000"}) == 0);  // -16384
  REQUIRE(run({"cansend", "vcan0", "285#0100"}) == 0);
  const auto again = published.wait_for(
      [&](const PanelSnapshot& s) { return !s.failsafe && s.controls[drive_x].axis < -0.4f; }, kPeerTimeoutMs, from);
  REQUIRE(again);

  // Silence: stale once the heartbeat consumer time (3 s) has passed.
  from = published.size();
  const auto quiet = std::chrono::steady_clock::now();
  const auto stale = published.wait_for(
      [](const PanelSnapshot& s) { return s.failsafe_reason.find("no heartbeat for") != std::string::npos; },
      3 * kPeerTimeoutMs, from);
  REQUIRE(stale);
  const auto after_ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - quiet).count();
  CHECK(after_ms < 3000 + 500);
  bridge->stop();
}
