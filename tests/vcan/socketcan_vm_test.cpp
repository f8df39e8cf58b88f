// socketcan:// against a real Linux CAN stack. Runs only inside the VM of
// tests/vcan/run_in_vcan_vm.sh, which brings up vcan0 (mtu 72, CAN FD) and
// vcan1 (mtu 16, classic) and puts can-utils' cansend and candump in PATH.
//
// Error frames: vcan has no controller, so the kernel never makes one on its
// own, but an error frame sent on vcan (cansend with CAN_ERR_FLAG in an
// 8-digit id, as candump -e prints them) reaches every raw socket whose
// CAN_RAW_ERR_FILTER asks for its class, exactly as a controller's would
// (net/can/af_can.c, can_rcv_filter). That is how the bus-off and
// error-passive paths of the bridge meet the real kernel here.

#include <catch2/catch.hpp>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "hil/io/can_bus.hpp"
#include "hil/io/can_error.hpp"
#include "hil/io/can_url.hpp"
#include "hil/io/candump_log.hpp"
#include "hil/io/socketcan_bus.hpp"
#include "msgs/clock.hpp"
#include "tests/hil/bridge_test_support.hpp"
#include "tests/vcan/vm_children.hpp"

extern char** environ;

using namespace rise::hil::io;
using rise::test::vm::Child;
using rise::test::vm::LinkUpGuard;
using rise::test::vm::Pipe;
using rise::test::vm::read_available;
using rise::test::vm::run;

namespace {

using Clock = std::chrono::steady_clock;

constexpr int kReceiveTimeoutMs = 2000;  // generous: the guest is emulated (TCG)
constexpr int kPeerTimeoutMs = 10000;

int remaining_ms(Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
  return left.count() > 0 ? static_cast<int>(left.count()) : 0;
}

void require_vm() {
  struct stat st {};
  if (::stat("/sys/class/net/vcan0", &st) != 0 || ::stat("/sys/class/net/vcan1", &st) != 0) {
    FAIL("no vcan0/vcan1: run this program with tests/vcan/run_in_vcan_vm.sh");
  }
}

std::unique_ptr<SocketCanBus> open_socketcan(const std::string& url) {
  const auto address = std::get<SocketCanAddress>(parse_can_url(url));
  auto bus = std::make_unique<SocketCanBus>(url, address);
  const IoStatus opened = bus->reopen();
  INFO(url << ": " << bus->last_error());
  REQUIRE(opened == IoStatus::Ok);
  return bus;
}

CanFrame make_frame(uint32_t id, bool extended, std::vector<uint8_t> bytes) {
  CanFrame f;
  f.id = id;
  f.extended = extended;
  f.len = static_cast<uint8_t>(bytes.size());
  std::copy(bytes.begin(), bytes.end(), f.data.begin());
  return f;
}

CanFrame make_fd_frame(uint32_t id, bool extended, uint8_t len) {
  CanFrame f;
  f.id = id;
  f.extended = extended;
  f.fd = true;
  f.brs = true;
  f.len = len;
  for (uint8_t i = 0; i < len; ++i) f.data[i] = static_cast<uint8_t>(i * 3 + 1);
  return f;
}

}  // namespace

TEST_CASE("socketcan carries classic and extended frames between two sockets with kernel timestamps",
          "[vcan]") {
  require_vm();
  auto sender = open_socketcan("socketcan://vcan0");
  auto receiver = open_socketcan("socketcan://vcan0");

  CanFrame remote = make_frame(0x7FF, false, {});
  remote.remote = true;
  remote.len = 2;
  const CanFrame sent = GENERATE_COPY(values<CanFrame>({
      make_frame(0x123, false, {0xDE, 0xAD, 0xBE, 0xEF}),
      make_frame(0x1ABCDEF0, true, {1, 2, 3, 4, 5, 6, 7, 8}),
      make_frame(0x000, false, {}),
      remote,
  }));
  INFO("id 0x" << std::hex << sent.id << (sent.extended ? " (29 bit)" : " (11 bit)"));

  const int64_t before_us = rise::msgs::wall_us();
  REQUIRE(sender->send(sent) == IoStatus::Ok);
  const int64_t after_send_us = rise::msgs::wall_us();

  CanFrame received;
  REQUIRE(receiver->receive(received, kReceiveTimeoutMs) == IoStatus::Ok);
  CHECK(same_content(received, sent));
  CHECK(received.remote == sent.remote);
  CHECK_FALSE(received.fd);
  // The kernel stamps the frame while send() delivers it to the local
  // sockets (vcan echoes in its xmit path); a stamp taken by receive()
  // itself would come after after_send_us.
  CHECK(received.timestamp_us >= before_us);
  CHECK(received.timestamp_us <= after_send_us);

  // CAN_RAW_RECV_OWN_MSGS is off: the sender does not read its own frame.
  CanFrame own;
  CHECK(sender->receive(own, 0) == IoStatus::Timeout);
}

TEST_CASE("socketcan carries a 64-byte CAN FD frame with bit-rate switch on an FD interface",
          "[vcan]") {
  require_vm();
  auto sender = open_socketcan("socketcan://vcan0");
  auto receiver = open_socketcan("socketcan://vcan0");
  CHECK(sender->fd_enabled());
  CHECK(receiver->fd_enabled());

  const uint8_t len = GENERATE(as<uint8_t>{}, 64, 12);
  const bool extended = GENERATE(true, false);
  const CanFrame sent = make_fd_frame(extended ? 0x18DAF110 : 0x456, extended, len);
  INFO("len " << int{len} << (extended ? ", 29-bit id" : ", 11-bit id"));
  REQUIRE(sender->send(sent) == IoStatus::Ok);

  CanFrame received;
  REQUIRE(receiver->receive(received, kReceiveTimeoutMs) == IoStatus::Ok);
  CHECK(same_content(received, sent));
  CHECK(received.fd);
  CHECK(received.brs);
  CHECK_FALSE(received.esi);
  CHECK(received.len == len);

  SECTION("a classic frame still passes on the FD socket") {
    const CanFrame classic = make_frame(0x321, false, {9, 8, 7});
    REQUIRE(sender->send(classic) == IoStatus::Ok);
    REQUIRE(receiver->receive(received, kReceiveTimeoutMs) == IoStatus::Ok);
    CHECK(same_content(received, classic));
    CHECK_FALSE(received.fd);
  }
}

TEST_CASE("socketcan refuses CAN FD frames on a classic interface", "[vcan]") {
  require_vm();
  auto sender = open_socketcan("socketcan://vcan1");
  auto receiver = open_socketcan("socketcan://vcan1");
  CHECK_FALSE(sender->fd_enabled());

  CHECK(sender->send(make_fd_frame(0x456, false, 64)) == IoStatus::Invalid);
  CHECK(sender->send(make_fd_frame(0x456, false, 8)) == IoStatus::Invalid);
  CHECK(sender->is_open());

  // The refused frames never reached the bus: the next frame read is this one.
  const CanFrame classic = make_frame(0x0AB, false, {1, 2, 3, 4, 5, 6, 7, 8});
  REQUIRE(sender->send(classic) == IoStatus::Ok);
  CanFrame received;
  REQUIRE(receiver->receive(received, kReceiveTimeoutMs) == IoStatus::Ok);
  CHECK(same_content(received, classic));
}

TEST_CASE("socketcan filter passes only the ids it matches", "[vcan]") {
  require_vm();
  auto sender = open_socketcan("socketcan://vcan0");

  struct Case {
    const char* url;
    std::vector<CanFrame> rejected;
    std::vector<CanFrame> accepted;
  };
  const Case c = GENERATE(values<Case>({
      {"socketcan://vcan0?filter=123:7FF",
       {make_frame(0x124, false, {1}), make_frame(0x123, true, {2}), make_frame(0x523, false, {3})},
       {make_frame(0x123, false, {4}), make_frame(0x123, false, {5, 5})}},
      {"socketcan://vcan0?filter=120:7F0",
       {make_frame(0x0F0, false, {1}), make_frame(0x130, false, {2}), make_frame(0x120, true, {3})},
       {make_frame(0x12A, false, {4}), make_frame(0x120, false, {5}), make_frame(0x12F, false, {6})}},
      {"socketcan://vcan0?filter=18DAF110:1FFFFFFF",
       {make_frame(0x18DAF111, true, {1}), make_frame(0x110, false, {2})},
       {make_frame(0x18DAF110, true, {3, 4})}},
      {"socketcan://vcan0?filter=100:700,18DAF100:1FFFFF00",
       {make_frame(0x200, false, {1}), make_frame(0x18DAF200, true, {2}), make_frame(0x100, true, {3})},
       {make_frame(0x1FF, false, {4}), make_frame(0x18DAF1AA, true, {5})}},
  }));
  INFO(c.url);
  auto filtered = open_socketcan(c.url);

  // Rejected and accepted frames interleaved: frames arrive in the order
  // sent, so each receive() returning exactly the next accepted frame proves
  // that no rejected frame came through, without waiting for silence.
  for (size_t i = 0; i < c.accepted.size() || i < c.rejected.size(); ++i) {
    if (i < c.rejected.size()) REQUIRE(sender->send(c.rejected[i]) == IoStatus::Ok);
    if (i < c.accepted.size()) REQUIRE(sender->send(c.accepted[i]) == IoStatus::Ok);
  }
  for (const CanFrame& expected : c.accepted) {
    CanFrame received;
    REQUIRE(filtered->receive(received, kReceiveTimeoutMs) == IoStatus::Ok);
    INFO("received id 0x" << std::hex << received.id);
    CHECK(same_content(received, expected));
  }
  CanFrame extra;
  CHECK(filtered->receive(extra, 0) == IoStatus::Timeout);
}

TEST_CASE("frames from can-utils cansend reach socketcan receive", "[vcan]") {
  require_vm();
  auto receiver = open_socketcan("socketcan://vcan0");

  SECTION("classic frame") {
    REQUIRE(run({"cansend", "vcan0", "123#DEADBEEF"}) == 0);
    CanFrame received;
    REQUIRE(receiver->receive(received, kReceiveTimeoutMs) == IoStatus::Ok);
    CHECK(same_content(received, make_frame(0x123, false, {0xDE, 0xAD, 0xBE, 0xEF})));
    CHECK(received.timestamp_us > 0);
  }
  SECTION("extended remote frame") {
    REQUIRE(run({"cansend", "vcan0", "1F334455#R3"}) == 0);
    CanFrame received;
    REQUIRE(receiver->receive(received, kReceiveTimeoutMs) == IoStatus::Ok);
    CHECK(received.id == 0x1F334455);
    CHECK(received.extended);
    CHECK(received.remote);
    CHECK(received.len == 3);
  }
  SECTION("64-byte CAN FD frame with bit-rate switch") {
    std::string text = "1ABCDEF0##1";
    const CanFrame expected = make_fd_frame(0x1ABCDEF0, true, 64);
    static const char kHex[] = "0123456789ABCDEF";
    for (uint8_t i = 0; i < 64; ++i) {
      text += kHex[expected.data[i] >> 4];
      text += kHex[expected.data[i] & 0xF];
    }
    REQUIRE(run({"cansend", "vcan0", text}) == 0);
    CanFrame received;
    REQUIRE(receiver->receive(received, kReceiveTimeoutMs) == IoStatus::Ok);
    CHECK(same_content(received, expected));
  }
}

TEST_CASE("can-utils candump sees the frames socketcan sends", "[vcan]") {
  require_vm();
  auto sender = open_socketcan("socketcan://vcan0");

  struct Case {
    CanFrame frame;
    std::vector<std::string> line_ends;  // candump -L: "(TIME) vcan0 ID#DATA"
  };
  const Case c = GENERATE_COPY(values<Case>({
      {make_frame(0x321, false, {0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08}),
       {" vcan0 321#0102030405060708"}},
      {make_frame(0x00ABCDEF, true, {0xCA, 0xFE}), {" vcan0 00ABCDEF#CAFE"}},
      // "##<flags>": BRS = 1; kernels since 6.0 add CANFD_FDF (4) on receive.
      {make_fd_frame(0x321, false, 12),
       {" vcan0 321##10104070A0D101316191C1F22", " vcan0 321##50104070A0D101316191C1F22"}},
  }));

  // candump binds its socket some time after it starts and prints nothing
  // until then, so keep sending until its one line (-n 1) appears; the
  // filter keeps other traffic out.
  Pipe out;
  REQUIRE(out.read_fd >= 0);
  Child candump({"candump", "-n", "1", "-L", "vcan0,321:7FF,00ABCDEF:1FFFFFFF"}, out.write_fd);
  REQUIRE(candump.started());
  out.close_write();

  std::string line;
  const auto deadline = Clock::now() + std::chrono::milliseconds(kPeerTimeoutMs);
  int sends = 0;
  while (line.find('\n') == std::string::npos && Clock::now() < deadline) {
    REQUIRE(sender->send(c.frame) == IoStatus::Ok);
    ++sends;
    line += read_available(out.read_fd, std::min(50, remaining_ms(deadline)));
  }
  INFO("candump printed '" << line << "' after " << sends << " sends");
  REQUIRE(line.find('\n') != std::string::npos);
  line.erase(line.find('\n'));
  CHECK(line.front() == '(');
  bool matched = false;
  for (const std::string& end : c.line_ends) {
    matched = matched || (line.size() >= end.size() &&
                          line.compare(line.size() - end.size(), end.size(), end) == 0);
  }
  CHECK(matched);
  CHECK(candump.wait_exit(kPeerTimeoutMs) == 0);
}

TEST_CASE("socketcan reports an interface taken down as Disconnected and reopens when it is up",
          "[vcan]") {
  require_vm();
  auto sender = open_socketcan("socketcan://vcan0");
  auto receiver = open_socketcan("socketcan://vcan0");
  LinkUpGuard restore("vcan0");

  REQUIRE(run({"ip", "link", "set", "vcan0", "down"}) == 0);
  CanFrame received;
  CHECK(receiver->receive(received, kReceiveTimeoutMs) == IoStatus::Disconnected);
  CHECK_FALSE(receiver->is_open());
  CHECK_THAT(receiver->last_error(), Catch::Contains("socketcan://vcan0: recvmsg: "));
  const CanFrame frame = make_frame(0x100, false, {0x11, 0x22});
  CHECK(sender->send(frame) == IoStatus::Disconnected);
  CHECK_FALSE(sender->is_open());
  CHECK(receiver->receive(received, 0) == IoStatus::Disconnected);

  SECTION("reopen on a down interface says so") {
    CHECK(sender->reopen() == IoStatus::Disconnected);
    CHECK_FALSE(sender->is_open());
    CHECK_THAT(sender->last_error(), Catch::Contains("down"));
  }

  REQUIRE(run({"ip", "link", "set", "vcan0", "up"}) == 0);
  REQUIRE(sender->reopen() == IoStatus::Ok);
  REQUIRE(receiver->reopen() == IoStatus::Ok);
  CHECK(sender->last_error().empty());
  REQUIRE(sender->send(frame) == IoStatus::Ok);
  REQUIRE(receiver->receive(received, kReceiveTimeoutMs) == IoStatus::Ok);
  CHECK(same_content(received, frame));
}

TEST_CASE("a receive waiting in another thread returns Disconnected when the interface goes down",
          "[vcan]") {
  require_vm();
  auto receiver = open_socketcan("socketcan://vcan0");
  LinkUpGuard restore("vcan0");

  // Whether the thread is already in poll() when the link drops or gets
  // there after, the answer must be Disconnected: a Timeout would mean the
  // waiting receive missed the kernel's POLLERR.
  std::atomic<bool> started{false};
  IoStatus status = IoStatus::Ok;
  std::thread waiter([&] {
    CanFrame frame;
    started.store(true);
    status = receiver->receive(frame, 3 * kReceiveTimeoutMs);
  });
  while (!started.load()) std::this_thread::yield();
  const int down = run({"ip", "link", "set", "vcan0", "down"});
  waiter.join();
  REQUIRE(down == 0);
  CHECK(status == IoStatus::Disconnected);
  CHECK_FALSE(receiver->is_open());
}

TEST_CASE("opening a missing or non-CAN interface fails with a clear message", "[vcan]") {
  require_vm();
  SECTION("no such interface") {
    try {
      open_can_bus("socketcan://vcan9");
      FAIL("opened socketcan://vcan9");
    } catch (const std::runtime_error& e) {
      CHECK_THAT(e.what(), Catch::StartsWith("socketcan://vcan9: no such CAN interface 'vcan9'"));
    }
  }
  SECTION("an interface that is not CAN") {
    try {
      open_can_bus("socketcan://lo");
      FAIL("opened socketcan://lo");
    } catch (const std::runtime_error& e) {
      CHECK_THAT(e.what(), Catch::StartsWith("socketcan://lo: 'lo' is gone or not a CAN interface"));
    }
  }
}

TEST_CASE("error frames from cansend arrive as error frames with the controller state they report", "[vcan]") {
  require_vm();
  auto receiver = open_socketcan("socketcan://vcan0");
  const auto next_error = [&] {
    CanFrame f;
    const auto deadline = Clock::now() + std::chrono::milliseconds(kPeerTimeoutMs);
    while (receiver->receive(f, remaining_ms(deadline)) == IoStatus::Ok)
      if (f.error) return f;
    FAIL("no error frame");
    return f;
  };
  REQUIRE(run({"cansend", "vcan0", "20000004#0010000000000000"}) == 0);
  CanFrame f = next_error();
  CHECK(f.id == 0x004);
  CHECK(describe_can_error(f).state == CanBusState::Passive);
  CHECK(can_error_text(f) == "controller-problem{rx-error-passive}");

  REQUIRE(run({"cansend", "vcan0", "20000240#0000000000007F80"}) == 0);
  f = next_error();
  const CanErrorReport busoff = describe_can_error(f);
  CHECK(busoff.state == CanBusState::BusOff);
  CHECK(busoff.tx_errors == uint8_t{0x7f});
  CHECK(busoff.rx_errors == uint8_t{0x80});
  CHECK(can_error_text(f) == "bus-off, error-counter-tx-rx{{127}{128}}");

  REQUIRE(run({"cansend", "vcan0", "20000100#0000000000000000"}) == 0);
  f = next_error();
  CHECK(describe_can_error(f).state == CanBusState::Active);
  CHECK(can_error_text(f) == "restarted-after-bus-off");
}

namespace {

// rise-hild's bridge on socketcan://vcan0 against the console emulator on a
// socket of its own on the same interface, as a console's controller and the
// host's would share a bus.
struct VcanBridge {
  rise::panels::PanelDefinition def = rise::hil::test::console();
  rise::hil::test::Published published;
  rise::hil::test::EmulatorThread console{def, "socketcan://vcan0"};
  rise::hil::Bridge bridge;

  VcanBridge()
      : bridge(def, open_buses(), [this](const rise::hil::PanelSnapshot& s) { published.add(s); }) {
    bridge.start();
  }
  ~VcanBridge() { bridge.stop(); }
  static std::vector<std::unique_ptr<CanBus>> open_buses() {
    std::vector<std::unique_ptr<CanBus>> buses;
    buses.push_back(open_can_bus("socketcan://vcan0"));
    return buses;
  }
  const rise::hil::ControlValue& value(const rise::hil::PanelSnapshot& s, const char* name) const {
    return s.controls[*def.find_control(name)];
  }
};

}  // namespace

TEST_CASE("the bridge on socketcan follows the emulated console, goes failsafe at bus-off and recovers at restart",
          "[vcan]") {
  require_vm();
  VcanBridge b;
  using rise::hil::PanelSnapshot;
  using rise::hil::test::set;
  b.console.apply(set(b.def, "deadman", 0, true));
  b.console.apply(set(b.def, "drive_y", 0.5f, false));
  auto ok = b.published.wait_for(
      [&](const PanelSnapshot& s) { return !s.failsafe && b.value(s, "drive_y").axis > 0.3f; }, kPeerTimeoutMs);
  REQUIRE(ok);
  CHECK(ok->sources[0].bus_state == CanBusState::Active);

  SECTION("error-passive is reported, and the panel stays usable") {
    const std::size_t from = b.published.size();
    REQUIRE(run({"cansend", "vcan0", "20000004#0020000000000000"}) == 0);
    auto passive = b.published.wait_for(
        [&](const PanelSnapshot& s) { return s.sources[0].bus_state == CanBusState::Passive; }, kPeerTimeoutMs, from);
    REQUIRE(passive);
    CHECK_FALSE(passive->failsafe);
    CHECK(passive->sources[0].error_frames == 1);
  }

  SECTION("bus-off puts the controls at their safe values at once; a restart brings them back") {
    const std::size_t from = b.published.size();
    const auto sent = Clock::now();
    REQUIRE(run({"cansend", "vcan0", "20000040#0000000000000000"}) == 0);
    // The snapshot that reports the bus-off (under TCG a late frame can
    // fail the panel stale a moment before it).
    auto off = b.published.wait_for(
        [](const PanelSnapshot& s) { return s.failsafe && s.sources[0].bus_state == CanBusState::BusOff; },
        kPeerTimeoutMs, from);
    REQUIRE(off);
    WARN("cansend bus-off -> failsafe PanelState: "
         << std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - sent).count()
         << " ms (includes spawning cansend under TCG)");
    CHECK(off->failsafe_reason == "console: CAN bus-off");
    CHECK(off->sources[0].bus_state == CanBusState::BusOff);
    CHECK(off->sources[0].bus_offs == 1);
    CHECK(b.value(*off, "drive_y").axis == 0.0f);
    CHECK(b.value(*off, "drive_y").forced_safe);

    // The console keeps sending while the error frame says bus-off: the state
    // must hold until the controller reports its restart...
    const std::size_t later = b.published.size();
    REQUIRE(run({"cansend", "vcan0", "20000100#0000000000000000"}) == 0);
    auto back = b.published.wait_for(
        [&](const PanelSnapshot& s) { return !s.failsafe && b.value(s, "drive_y").axis > 0.3f; }, kPeerTimeoutMs,
        later);
    REQUIRE(back);
    CHECK(back->sources[0].bus_state == CanBusState::Active);
    CHECK(back->sources[0].error_frames == 2);
  }
}

TEST_CASE("can-utils candump sees the bridge's feedback frames on the real bus", "[vcan]") {
  require_vm();
  Pipe out;
  REQUIRE(out.read_fd >= 0);
  // The indicators frame of node 0 (0x210), sent at the feedback rate.
  Child candump({"candump", "-n", "2", "-L", "vcan0,210:7FF"}, out.write_fd);
  REQUIRE(candump.started());
  out.close_write();
  VcanBridge b;
  const int exit = candump.wait_exit(kPeerTimeoutMs);
  const std::string text = read_available(out.read_fd, 1000);
  INFO("candump printed: " << text);
  CHECK(exit == 0);
  // "(TIME) vcan0 210#LL.." twice; byte 0 = LED bits with power lit.
  CHECK(text.find("vcan0 210#") != std::string::npos);
}

TEST_CASE("a frame typed into can-utils cansend reaches the PanelState through a dbc source", "[vcan]") {
  require_vm();
  // A joystick box described by a DBC of its own: 0x500, a signed 16-bit
  // stick and a trigger bit (Intel byte order).
  const std::string dbc = "/tmp/joy_box.dbc";
  {
    std::FILE* f = std::fopen(dbc.c_str(), "w");
    REQUIRE(f);
    std::fputs("VERSION \"\"\n\nBU_: JOY\n\n"
               "BO_ 1280 JOY: 8 JOY\n"
               " SG_ STICK_Y : 0|16@1- (1,0) [-32768|32767] \"\" Vector__XXX\n"
               " SG_ TRIGGER : 16|1@1+ (1,0) [0|1] \"\" Vector__XXX\n",
               f);
    std::fclose(f);
  }
  const auto def = rise::panels::parse_panel_definition(
      "panel: joy-box\n"
      "sources:\n"
      "  - {name: box, protocol: dbc, dbc: " + dbc + ", timeout_ms: 10000}\n"
      "controls:\n"
      "  - {name: stick_y, kind: axis, signal: JOY.STICK_Y, range: [-32768, 32767], safe: 0}\n"
      "  - {name: trigger, kind: button, signal: JOY.TRIGGER, safe: false}\n",
      "/tmp/joy_box.yaml");
  rise::hil::test::Published published;
  std::vector<std::unique_ptr<CanBus>> buses;
  buses.push_back(open_can_bus("socketcan://vcan0"));
  rise::hil::Bridge bridge(def, std::move(buses), [&](const rise::hil::PanelSnapshot& s) { published.add(s); });
  bridge.start();
  const std::size_t stick = *def.find_control("stick_y"), trigger = *def.find_control("trigger");

  REQUIRE(run({"cansend", "vcan0", "500#0040010000000000"}) == 0);  // 0x4000 = 16384, trigger on
  auto s = published.wait_for([](const rise::hil::PanelSnapshot& p) { return !p.failsafe; }, kPeerTimeoutMs);
  REQUIRE(s);
  CHECK(s->controls[stick].axis == Approx(16384.5 / 32767.5).margin(1e-3));
  CHECK(s->controls[trigger].pressed);

  const std::size_t from = published.size();
  REQUIRE(run({"cansend", "vcan0", "500#00C0000000000000"}) == 0);  // 0xC000 = -16384, trigger off
  s = published.wait_for(
      [&](const rise::hil::PanelSnapshot& p) { return !p.controls[trigger].pressed; }, kPeerTimeoutMs, from);
  REQUIRE(s);
  CHECK(s->controls[stick].axis == Approx(-16383.5 / 32767.5).margin(1e-3));
  bridge.stop();
}

TEST_CASE("the bridge fails safe within a publish period when the interface goes down and recovers when it is up",
          "[vcan]") {
  require_vm();
  LinkUpGuard restore("vcan0");
  VcanBridge b;
  using rise::hil::PanelSnapshot;
  using rise::hil::test::set;
  b.console.apply(set(b.def, "deadman", 0, true));
  b.console.apply(set(b.def, "drive_y", 0.5f, false));
  REQUIRE(b.published.wait_for(
      [&](const PanelSnapshot& s) { return !s.failsafe && b.value(s, "drive_y").axis > 0.3f; }, kPeerTimeoutMs));

  const std::size_t from = b.published.size();
  const int64_t before_us = rise::msgs::monotonic_us();
  REQUIRE(run({"ip", "link", "set", "vcan0", "down"}) == 0);
  const int64_t after_us = rise::msgs::monotonic_us();
  auto down = b.published.wait_for([](const PanelSnapshot& s) { return s.failsafe; }, kPeerTimeoutMs, from);
  REQUIRE(down);
  const int64_t period_us = b.def.publish_period_us();
  WARN("link down -> failsafe PanelState: " << static_cast<double>(down->time_us - after_us) / 1000.0 << " ms after `ip link set down` "
       << "returned (it ran " << static_cast<double>(after_us - before_us) / 1000.0 << " ms)");
  // The kernel drops the link inside the command: the failsafe message is
  // due within one publish period of its return (plus the guest's scheduling).
  CHECK(down->time_us - after_us <= period_us + 5000);
  CHECK(down->failsafe_reason == "console: disconnected");
  CHECK(b.value(*down, "drive_y").axis == 0.0f);
  CHECK_FALSE(down->sources[0].connected);

  const std::size_t later = b.published.size();
  REQUIRE(run({"ip", "link", "set", "vcan0", "up"}) == 0);
  auto up = b.published.wait_for(
      [&](const PanelSnapshot& s) { return !s.failsafe && b.value(s, "drive_y").axis > 0.3f; }, kPeerTimeoutMs, later);
  REQUIRE(up);
  CHECK(up->sources[0].reconnects >= 1);
}

TEST_CASE("rise-panel replay plays a capture onto vcan0 and candump shows it frame for frame", "[vcan]") {
  require_vm();
  // 50 frames 4 ms apart: classic, 29-bit, empty, and a remote frame.
  const std::string capture = "/tmp/replay_capture.log";
  std::vector<std::string> expected;  // "ID#DATA" as candump -L prints them
  {
    std::FILE* f = std::fopen(capture.c_str(), "w");
    REQUIRE(f);
    for (int i = 0; i < 50; ++i) {
      CanFrame c;
      c.id = i % 5 == 0 ? 0x1ABC0000u + static_cast<uint32_t>(i) : 0x200u + static_cast<uint32_t>(i);
      c.extended = i % 5 == 0;
      c.remote = i == 7;
      c.len = static_cast<uint8_t>(c.remote ? 0 : i % 9);
      for (uint8_t b = 0; b < c.len; ++b) c.data[b] = static_cast<uint8_t>(i + b);
      c.timestamp_us = 1'700'000'000'000'000 + int64_t{i} * 4000;
      const std::string line = format_candump_line(c, "can0");
      std::fprintf(f, "%s\n", line.c_str());
      expected.push_back(line.substr(line.rfind(' ') + 1));
    }
    std::fclose(f);
  }
  Pipe out;
  REQUIRE(out.read_fd >= 0);
  Child candump({"candump", "-n", "50", "-L", "vcan0"}, out.write_fd);
  REQUIRE(candump.started());
  out.close_write();
  // candump binds its socket some time after it starts: the replay begins
  // once the kernel lists its receiver (candump without a filter is an
  // "rx_all" entry of vcan0 in /proc/net/can/rcvlist_all).
  const auto listening = [] {
    std::FILE* f = std::fopen("/proc/net/can/rcvlist_all", "r");
    if (!f) return false;
    char line[256];
    bool found = false;
    while (std::fgets(line, sizeof line, f)) {
      const std::string l(line);
      if (l.find("vcan0") != std::string::npos && l.find("no entry") == std::string::npos) found = true;
    }
    std::fclose(f);
    return found;
  };
  const auto deadline = Clock::now() + std::chrono::milliseconds(kPeerTimeoutMs);
  while (!listening() && Clock::now() < deadline) std::this_thread::yield();
  REQUIRE(listening());
  REQUIRE(run({RISE_PANEL_BIN, "replay", capture, "--to", "socketcan://vcan0", "--progress-every", "0"}) == 0);
  CHECK(candump.wait_exit(kPeerTimeoutMs) == 0);
  const std::string text = read_available(out.read_fd, 1000);
  std::vector<std::string> got;
  std::vector<double> times;
  for (std::size_t at = 0; at < text.size();) {
    const auto nl = text.find('\n', at);
    const std::string line = text.substr(at, nl - at);
    at = nl == std::string::npos ? text.size() : nl + 1;
    if (line.empty()) continue;
    got.push_back(line.substr(line.rfind(' ') + 1));  // "(TIME) vcan0 ID#DATA"
    times.push_back(std::stod(line.substr(1, line.find(')') - 1)));
  }
  INFO("candump printed:\n" << text);
  REQUIRE(got.size() == expected.size());
  CHECK(got == expected);
  // The capture's timing on the bus (kernel receive stamps): 0.196 s first to last.
  CHECK(times.back() - times.front() == Approx(0.196).margin(0.03));
}
