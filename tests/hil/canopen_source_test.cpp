// A CANopen console (protocol canopen) through the live bridge on an
// in-memory bus: against the node emulator (panels/canopen_emulator) and
// against raw frames written with the bytes of CiA 301, so the bridge is
// held to the standard, not only to our own emulator.

#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>

#include "firmware_protocol/canopen.hpp"
#include "hil/canopen_source.hpp"
#include "hil/source_factory.hpp"
#include "panels/canopen_emulator.hpp"
#include "tests/hil/bridge_test_support.hpp"

namespace co = rise::firmware_protocol::canopen;
using rise::hil::PanelSnapshot;
using rise::hil::test::Published;

namespace {

rise::panels::PanelDefinition canopen_console() {
  return rise::panels::load_panel_definition(std::string(RISE_SOURCE_DIR) +
                                             "/panels/definitions/rise_console_canopen.yaml");
}

rise::panels::TimelineEvent directive(rise::panels::TimelineEvent::Kind kind, uint8_t status = 0) {
  rise::panels::TimelineEvent e;
  e.kind = kind;
  e.status = status;
  return e;
}

// The node's firmware on a bus, in its own thread.
class CanopenNodeThread {
 public:
  CanopenNodeThread(const rise::panels::PanelDefinition& def, const std::string& url)
      : emulator_(def, 0), bus_(rise::hil::io::open_can_bus(url)) {
    thread_ = std::thread([this] { run(); });
  }
  ~CanopenNodeThread() {
    running_ = false;
    thread_.join();
  }
  void apply(const rise::panels::TimelineEvent& e) {
    std::lock_guard lock(mutex_);
    emulator_.apply(e);
  }
  std::optional<double> feedback(const std::string& name) {
    std::lock_guard lock(mutex_);
    return emulator_.feedback(name);
  }
  int64_t syncs() {
    std::lock_guard lock(mutex_);
    return emulator_.syncs_seen();
  }
  int64_t heartbeats() {
    std::lock_guard lock(mutex_);
    return emulator_.heartbeats_sent();
  }
  co::NmtState state() {
    std::lock_guard lock(mutex_);
    return emulator_.state();
  }
  // Until `done` holds for the node, checked as each frame it takes is
  // handled and after each tick that sent one; false after timeout_ms.
  bool wait_until(const std::function<bool(rise::panels::CanopenEmulator&)>& done, int timeout_ms) {
    std::unique_lock lock(mutex_);
    return handled_.wait_for(lock, std::chrono::milliseconds(timeout_ms), [&] { return done(emulator_); });
  }

 private:
  void run() {
    rise::hil::io::CanFrame f;
    while (running_) {
      bool sent = false;
      {
        std::lock_guard lock(mutex_);
        sent = emulator_.tick(*bus_, rise::msgs::monotonic_us()) > 0;
      }
      if (sent) handled_.notify_all();
      while (bus_->receive(f, 1) == rise::hil::io::IoStatus::Ok) {
        {
          std::lock_guard lock(mutex_);
          emulator_.on_frame(*bus_, f, rise::msgs::monotonic_us());
        }
        handled_.notify_all();
      }
    }
  }
  std::mutex mutex_;
  std::condition_variable handled_;
  rise::panels::CanopenEmulator emulator_;
  std::unique_ptr<rise::hil::io::CanBus> bus_;
  std::atomic<bool> running_{true};
  std::thread thread_;
};

// A peer on the bus that writes frames by hand and keeps what it reads.
struct RawPeer {
  explicit RawPeer(const std::string& url) : bus(rise::hil::io::open_can_bus(url)) {}
  void send(uint32_t id, std::vector<uint8_t> data) {
    rise::hil::io::CanFrame f;
    f.id = id;
    f.len = static_cast<uint8_t>(data.size());
    std::copy(data.begin(), data.end(), f.data.begin());
    REQUIRE(bus->send(f) == rise::hil::io::IoStatus::Ok);
  }
  // The next frame with `id` within timeout_ms (others are kept in `seen`).
  std::optional<rise::hil::io::CanFrame> wait(uint32_t id, int timeout_ms) {
    const int64_t end = rise::msgs::monotonic_us() + 1000 * timeout_ms;
    rise::hil::io::CanFrame f;
    while (rise::msgs::monotonic_us() < end)
      if (bus->receive(f, 5) == rise::hil::io::IoStatus::Ok) {
        seen.push_back(f);
        if (f.id == id) return f;
      }
    return std::nullopt;
  }
  std::unique_ptr<rise::hil::io::CanBus> bus;
  std::vector<rise::hil::io::CanFrame> seen;
};

std::vector<uint8_t> payload(const rise::hil::io::CanFrame& f) { return {f.data.begin(), f.data.begin() + f.len}; }

}  // namespace

TEST_CASE("a canopen console is reset, started, read from its PDOs and shown its LEDs", "[hil][canopen]") {
  const auto def = canopen_console();
  CanopenNodeThread node(def, "mem://canopen_live");
  std::vector<std::unique_ptr<rise::hil::SourceTransport>> transports;
  transports.push_back(rise::hil::open_source(def, 0, "mem://canopen_live"));
  REQUIRE(dynamic_cast<rise::hil::CanopenSource*>(transports[0].get()));
  Published published;
  rise::hil::Bridge bridge(def, std::move(transports), [&](const PanelSnapshot& s) { published.add(s); });
  bridge.start();
  const std::size_t drive_y = *def.find_control("drive_y");
  const std::size_t camera = *def.find_control("camera");

  REQUIRE(published.wait_for([](const PanelSnapshot& s) { return !s.failsafe; }, 3000));
  CHECK(node.state() == co::NmtState::Operational);
  node.apply(rise::hil::test::set(def, "deadman", 0, true));
  node.apply(rise::hil::test::set(def, "drive_y", 0.5f, false));
  rise::panels::TimelineEvent rear;
  rear.control = camera;
  rear.position = 2;
  node.apply(rear);
  const auto driving = published.wait_for(
      [&](const PanelSnapshot& s) {
        return !s.failsafe && s.deadman && s.controls[camera].position == 2 &&
               std::abs(s.controls[drive_y].axis - 0.5f) < 0.06f;
      },
      2000);
  REQUIRE(driving);

  SECTION("SYNC comes every 10 ms (0x1006)") {
    const int64_t before = node.syncs();
    std::this_thread::sleep_for(std::chrono::milliseconds(500));  // measuring a rate over a span, not syncing
    const int64_t syncs = node.syncs() - before;
    CHECK(syncs >= 35);  // 50 expected; a loaded machine delays some, never bursts
    CHECK(syncs <= 55);
  }
  SECTION("the LEDs and the display are written into RPDO1") {
    rise::hil::FeedbackRequest request;
    request.displays.push_back({"speed", 0.42f});
    request.leds.push_back({"deadman", true});
    bridge.set_feedback(request);
    node.wait_until([](rise::panels::CanopenEmulator& e) { return e.feedback("speed") == 0.42; }, 2000);
    CHECK(node.feedback("speed") == Approx(0.42).margin(1e-9));
    CHECK(node.feedback("power") == 1.0);
    CHECK(node.feedback("fault") == 0.0);
    CHECK(node.feedback("deadman") == 1.0);
  }
  SECTION("a node that leaves Operational fails safe at once and is started again after it boots up") {
    const std::size_t from = published.size();
    const int64_t t0 = rise::msgs::monotonic_us();
    node.apply(directive(rise::panels::TimelineEvent::Kind::Status, 2));  // fault: pre-operational on its own
    const auto safe = published.wait_for(
        [&](const PanelSnapshot& s) { return s.failsafe && s.controls[drive_y].forced_safe; }, 1000, from);
    REQUIRE(safe);
    CHECK(safe->failsafe_reason.find("node 5 pre-operational") != std::string::npos);
    CHECK(safe->time_us - t0 < 60'000);  // its next heartbeat (sent at once) + one publish period
    CHECK(safe->controls[drive_y].axis == 0.0f);
    // Not started again while it stays heard: still pre-operational and
    // safe after three more of its heartbeats (0x1017: every 100 ms).
    const int64_t beats = node.heartbeats();
    CHECK(node.wait_until([&](rise::panels::CanopenEmulator& e) { return e.heartbeats_sent() >= beats + 3; }, 2000));
    CHECK(node.state() == co::NmtState::PreOperational);
    CHECK(bridge.snapshot().failsafe);
    // Power cycle: boot-up, NMT start, PDOs again. Every snapshot from here
    // on is failsafe until the node is started again.
    const std::size_t cycled = published.size();
    node.apply(directive(rise::panels::TimelineEvent::Kind::Silent));
    node.apply(directive(rise::panels::TimelineEvent::Kind::Resume));
    node.apply(rise::hil::test::set(def, "deadman", 0, true));
    node.apply(rise::hil::test::set(def, "drive_y", 0.5f, false));
    REQUIRE(published.wait_for(
        [&](const PanelSnapshot& s) { return !s.failsafe && std::abs(s.controls[drive_y].axis - 0.5f) < 0.06f; },
        3000, cycled));
    CHECK(node.state() == co::NmtState::Operational);
  }
  SECTION("a silent node is stale within the heartbeat consumer time and one publish period") {
    const std::size_t from = published.size();
    const int64_t t0 = rise::msgs::monotonic_us();
    node.apply(directive(rise::panels::TimelineEvent::Kind::Silent));
    // TPDO1 (every SYNC: stale after 3 periods, 30 ms) says it first...
    const auto stale = published.wait_for([](const PanelSnapshot& s) { return s.failsafe; }, 2000, from);
    REQUIRE(stale);
    CHECK(stale->failsafe_reason.find("node 5: stale (no TPDO1 for") != std::string::npos);
    CHECK(stale->time_us - t0 < 80'000);  // 30 + one publish period + scheduling
    // ...then the heartbeat consumer time (150 ms) + one publish period + scheduling.
    const auto no_heartbeat = published.wait_for(
        [](const PanelSnapshot& s) { return s.failsafe_reason.find("no heartbeat for") != std::string::npos; }, 2000,
        from);
    REQUIRE(no_heartbeat);
    CHECK(no_heartbeat->time_us - t0 < 200'000);
  }
  bridge.stop();
}

TEST_CASE("the bridge follows raw CiA 301 frames: boot-up, heartbeat states, TPDOs", "[hil][canopen]") {
  const auto def = canopen_console();
  RawPeer peer("mem://canopen_raw");
  std::vector<std::unique_ptr<rise::hil::SourceTransport>> transports;
  transports.push_back(rise::hil::open_source(def, 0, "mem://canopen_raw"));
  Published published;
  rise::hil::Bridge bridge(def, std::move(transports), [&](const PanelSnapshot& s) { published.add(s); });
  bridge.start();
  const std::size_t drive_x = *def.find_control("drive_x");
  const std::size_t drive_y = *def.find_control("drive_y");
  const std::size_t estop = *def.find_control("estop");

  // At open: NMT Reset Communication of node 5 (000#8205).
  const auto reset = peer.wait(0x000, 1000);
  REQUIRE(reset);
  CHECK(payload(*reset) == std::vector<uint8_t>{0x82, 0x05});
  // SYNC (080#, no data) every 10 ms.
  const auto sync = peer.wait(0x080, 1000);
  REQUIRE(sync);
  CHECK(sync->len == 0);
  // Boot-up 705#00 → NMT Start Remote Node 000#0105.
  peer.send(0x705, {0x00});
  const auto start = peer.wait(0x000, 1000);
  REQUIRE(start);
  CHECK(payload(*start) == std::vector<uint8_t>{0x01, 0x05});
  CHECK(bridge.snapshot().failsafe);
  // Operational; TPDO1: sticks LX=+16384 (0x4000) LY=-16384 (0xC000), TPDO2: dead-man + e-stop released, camera 0.
  peer.send(0x705, {0x05});
  peer.send(0x185, {0x00, 0x40, 0x00, 0xC0, 0x00, 0x00, 0x00, 0x00});
  peer.send(0x285, {0x01, 0x00});
  const auto live = published.wait_for(
      [&](const PanelSnapshot& s) {
        return !s.failsafe && std::abs(s.controls[drive_x].axis - 0.5f) < 0.06f &&
               std::abs(s.controls[drive_y].axis + 0.5f) < 0.06f && !s.controls[estop].pressed;
      },
      1000);
  REQUIRE(live);

  SECTION("a pre-operational heartbeat fails the panel safe") {
    const std::size_t from = published.size();
    peer.send(0x705, {0x7F});
    const auto safe = published.wait_for([](const PanelSnapshot& s) { return s.failsafe; }, 500, from);
    REQUIRE(safe);
    CHECK(safe->failsafe_reason.find("node 5 pre-operational") != std::string::npos);
    CHECK(safe->controls[drive_x].forced_safe);
    CHECK(safe->controls[estop].pressed);  // the e-stop's safe value
  }
  SECTION("no heartbeat within 150 ms is stale") {
    const std::size_t from = published.size();
    const auto stale = published.wait_for(
        [](const PanelSnapshot& s) { return s.failsafe && s.failsafe_reason.find("heartbeat") != std::string::npos; },
        1000, from);
    REQUIRE(stale);
  }
  SECTION("a TPDO shorter than its mapping is counted and fails the check") {
    peer.send(0x705, {0x05});
    peer.send(0x185, {0x00, 0x40, 0x00});
    const auto bad = published.wait_for(
        [](const PanelSnapshot& s) { return s.sources[0].check_failed; }, 500, published.size());
    REQUIRE(bad);
    CHECK(bad->sources[0].errors[static_cast<std::size_t>(rise::firmware_protocol::DecodeError::BadLength)] == 1);
  }
  SECTION("a malformed heartbeat is counted and dropped") {
    peer.send(0x705, {0x05, 0x00});
    peer.send(0x705, {0x42});
    const auto counted = published.wait_for(
        [](const PanelSnapshot& s) {
          using E = rise::firmware_protocol::DecodeError;
          return s.sources[0].errors[static_cast<std::size_t>(E::BadLength)] == 1 &&
                 s.sources[0].errors[static_cast<std::size_t>(E::BadValue)] == 1;
        },
        500, published.size());
    CHECK(counted);
  }
  bridge.stop();
}
