// rise-hild --record on live runs in separate processes (console emulator →
// socketcand or Modbus TCP on loopback → rise-hild → LCM multicast, or a
// HID recording played as the device), then `rise-hild verify` on what it
// recorded; the recordings' third-party readers: python-can's candump log
// reader and lcm-logplayer.

#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <thread>

#include "hil/io/can_log.hpp"
#include "hil/io/hid_recording.hpp"
#include "hil/io/recording_bus.hpp"
#include "msgs/channels.hpp"
#include "process/child_process.hpp"
#include "rise_msgs/PanelState.hpp"
#include "tests/integration/integration_support.hpp"

using rise::process::ChildProcess;
using rise::test::kBin;
using rise::test::kSource;
using rise::test::python_can_available;

namespace {
const std::string kLcm = rise::msgs::kDefaultLcmUrl;

std::string port_text(int offset) { return std::to_string(32000 + (::getpid() * 7 + offset) % 20000); }

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}


struct TempDir {
  std::string path;
  explicit TempDir(const std::string& name)
      : path(std::filesystem::temp_directory_path() / (name + "-" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~TempDir() { std::filesystem::remove_all(path); }
};

// Runs `rise-hild verify ARGS...`; its exit code, its output in `output`.
int verify(const std::vector<std::string>& args, const std::string& log, std::string& output) {
  std::vector<std::string> argv{kBin + "/rise-hild", "verify"};
  argv.insert(argv.end(), args.begin(), args.end());
  ChildProcess v(argv, log);
  const int rc = v.wait_for(60000);
  output = slurp(log);
  return rc;
}

// A live session: the emulator plays the recorded sessions' timeline and
// exits; rise-hild records it and is stopped by SIGTERM once the console is gone.
void record_live_session(const std::string& panel, const std::string& hild_source,
                         const std::vector<std::string>& emulator_transport, const std::string& id,
                         const std::string& dir,
                         const std::string& script = kSource + "/tests/data/replay/session.txt") {
  std::vector<std::string> emulate{kBin + "/rise-panel", "emulate", "--panel", panel, "--script", script,
                                   "--start-on-feedback"};
  emulate.insert(emulate.end(), emulator_transport.begin(), emulator_transport.end());
  ChildProcess panel_process(emulate, dir + "/rise-panel.log");
  ChildProcess hild({kBin + "/rise-hild", "--panel", panel, "--source", hild_source, "--id", id, "--lcm", kLcm,
                     "--record", dir + "/rec"},
                    dir + "/rise-hild.log");
  // The script starts on the daemon's first feedback and ends with @end.
  REQUIRE(panel_process.wait_for(20000) == 0);
  CHECK(hild.stop() == 0);
  INFO(slurp(dir + "/rise-hild.log"));
  CHECK(slurp(dir + "/rise-hild.log").find("PanelState events into " + dir + "/rec") != std::string::npos);
}

std::vector<rise_msgs::PanelState> read_states(const std::string& path) {
  std::vector<rise_msgs::PanelState> out;
  lcm::LogFile log(path, "r");
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    rise_msgs::PanelState m;
    if (m.decode(e->data, 0, static_cast<int>(e->datalen)) > 0) out.push_back(m);
  }
  return out;
}

// What python-can 4.1's CanutilsLogReader makes of one of our records, in
// python_can_read_log.py's layout. It knows only the bus-error class of error
// frames as errors (without channel or data); other error classes come out
// as 29-bit frames whose id is the class.
std::string python_can_view(const rise::hil::io::CanLogRecord& r) {
  const auto& f = r.frame;
  char head[96];
  const double ts = static_cast<double>(f.timestamp_us) * 1e-6;
  if (f.error && (f.id & 0x80u) != 0) {
    std::snprintf(head, sizeof head, "%.6f None 0 ext=1 rtr=0 fd=0 brs=0 esi=0 err=1 rx=1 dlc=0 -", ts);
    return head;
  }
  std::snprintf(head, sizeof head, "%.6f %s %X ext=%d rtr=%d fd=%d brs=%d esi=%d err=0 rx=%d dlc=%d ", ts,
                r.channel.c_str(), f.id, f.extended || f.error ? 1 : 0, f.remote ? 1 : 0, f.fd ? 1 : 0, f.brs ? 1 : 0,
                f.esi ? 1 : 0, r.tx ? 0 : 1, f.len);
  std::string out = head;
  if (f.remote || f.len == 0) return out + "-";
  static const char* digits = "0123456789ABCDEF";
  for (std::size_t i = 0; i < f.len; ++i) {
    out += digits[f.data[i] >> 4];
    out += digits[f.data[i] & 0xF];
  }
  return out;
}

// python-can's view of `log` next to ours, line by line; timestamps within 1 µs
// (python prints a double).
void check_python_can_reads(const std::string& log, const std::string& dir) {
  ChildProcess python({"/usr/bin/python3", kSource + "/tests/integration/python_can_read_log.py", log,
                       dir + "/python-view.txt"},
                      dir + "/python.log");
  REQUIRE(python.wait_for(30000) == 0);
  const auto ours = rise::hil::io::read_can_log(log);
  std::ifstream in(dir + "/python-view.txt");
  std::vector<std::string> theirs;
  for (std::string l; std::getline(in, l);) theirs.push_back(l);
  REQUIRE(theirs.size() == ours.size());
  for (std::size_t i = 0; i < ours.size(); ++i) {
    const std::string expected = python_can_view(ours[i]);
    INFO("line " << i + 1 << ": python-can: " << theirs[i] << "\n              ours: " << expected);
    const auto cut = [](const std::string& s) { return s.substr(s.find(' ')); };
    CHECK(cut(theirs[i]) == cut(expected));
    CHECK(std::fabs(std::stod(theirs[i]) - std::stod(expected)) <= 1.5e-6);
  }
}
}  // namespace

TEST_CASE("a live CAN session recorded with --record verifies against its own PanelState log, and one changed "
          "byte or a cut line does not",
          "[integration]") {
  TempDir dir("rise-record-can");
  const std::string bus = "127.0.0.1:" + port_text(0) + "/can0";
  const std::string id = "rec" + std::to_string(::getpid());
  const std::string panel = kSource + "/panels/definitions/rise_console.yaml";
  record_live_session(panel, "socketcand://" + bus, {"--can", "socketcand+listen://" + bus}, id, dir.path);
  const std::string rec = dir.path + "/rec";
  REQUIRE(std::filesystem::exists(rec + "/console.log"));
  REQUIRE(std::filesystem::exists(rec + "/panel_state.lcmlog"));
  const auto states = read_states(rec + "/panel_state.lcmlog");
  CHECK(states.size() > 150);

  std::string out;
  INFO("logs in " << dir.path);
  CHECK(verify({"--panel", panel, "--record-dir", rec}, dir.path + "/verify.log", out) == 0);
  CHECK(out.rfind("pass: " + std::to_string(states.size()) + " of " + std::to_string(states.size()), 0) == 0);
  // The same through --capture/--golden and --id.
  CHECK(verify({"--panel", panel, "--capture", rec + "/console.log", "--golden", rec + "/panel_state.lcmlog", "--id",
                id},
               dir.path + "/verify2.log", out) == 0);

  // One data byte changed in the 200th frame the daemon received.
  std::vector<std::string> lines;
  {
    std::ifstream in(rec + "/console.log");
    for (std::string l; std::getline(in, l);) lines.push_back(l);
  }
  std::size_t received = 0, target = 0;
  for (std::size_t i = 0; i < lines.size() && !target; ++i)
    if (lines[i].size() > 2 && lines[i].substr(lines[i].size() - 2) == " R" && ++received == 200) target = i;
  REQUIRE(target > 0);
  std::filesystem::create_directories(dir.path + "/changed");
  std::filesystem::copy_file(rec + "/panel_state.lcmlog", dir.path + "/changed/panel_state.lcmlog");
  {
    auto changed = lines;
    const std::size_t at = changed[target].find('#') + 4;  // a payload byte: the CRC no longer fits
    changed[target][at] = changed[target][at] == '0' ? '1' : '0';
    std::ofstream o(dir.path + "/changed/console.log");
    for (const auto& l : changed) o << l << "\n";
  }
  CHECK(verify({"--panel", panel, "--record-dir", dir.path + "/changed"}, dir.path + "/verify-changed.log", out) == 1);
  CHECK(out.find("FAIL: first difference at t=") != std::string::npos);
  // The panel failsafe when a publish fell inside the failure, else only the CRC count tells.
  CHECK((out.find("failsafe: expected false") != std::string::npos ||
         out.find("console.crc_errors: expected") != std::string::npos));

  // A line cut inside a byte (a recorder killed mid-write) is bad input: file and line.
  {
    auto cut = lines;
    cut[target] = cut[target].substr(0, cut[target].find('#') + 4);
    std::ofstream o(dir.path + "/changed/console.log");
    for (const auto& l : cut) o << l << "\n";
  }
  CHECK(verify({"--panel", panel, "--record-dir", dir.path + "/changed"}, dir.path + "/verify-cut.log", out) == 2);
  CHECK(out.find("console.log:" + std::to_string(target + 1) + ": not a candump frame line") != std::string::npos);

  // Third-party readers of what was recorded.
  if (python_can_available())
    check_python_can_reads(rec + "/console.log", dir.path);
  else
    WARN("python-can check skipped: /usr/bin/python3 with python3-can (Debian) is not installed");

  // lcm-logplayer plays the PanelState log onto multicast; every message arrives as recorded.
  lcm::LCM lcm(kLcm);
  REQUIRE(lcm.good());
  struct Received {
    std::vector<rise_msgs::PanelState> messages;
    void on(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::PanelState* m) { messages.push_back(*m); }
  } got;
  lcm::Subscription* sub = lcm.subscribe(rise::msgs::panel_state_channel(id), &Received::on, &got);
  sub->setQueueCapacity(static_cast<int>(states.size()) + 10);
  ChildProcess player({"/usr/bin/lcm-logplayer", "--lcm-url=" + kLcm, "--speed=4", rec + "/panel_state.lcmlog"},
                      dir.path + "/lcm-logplayer.log");
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (got.messages.size() < states.size() && std::chrono::steady_clock::now() < deadline) lcm.handleTimeout(100);
  CHECK(player.wait_for(10000) == 0);
  REQUIRE(got.messages.size() == states.size());
  for (std::size_t i = 0; i < states.size(); ++i) {
    CHECK(got.messages[i].seq == states[i].seq);
    CHECK(got.messages[i].utime == states[i].utime);
    CHECK(got.messages[i].failsafe_reason == states[i].failsafe_reason);
  }
  lcm.unsubscribe(sub);
}

TEST_CASE("a live Modbus TCP session recorded with --record verifies against its own PanelState log",
          "[integration]") {
  TempDir dir("rise-record-modbus");
  const std::string port = port_text(1);
  const std::string id = "mrec" + std::to_string(::getpid());
  const std::string panel = kSource + "/panels/definitions/rise_console_modbus.yaml";
  record_live_session(panel, "modbus+tcp://127.0.0.1:" + port,
                      {"--modbus", "modbus+tcp-listen://127.0.0.1:" + port + "?unit=1"}, id, dir.path);
  const std::string rec = dir.path + "/rec";
  const std::string trace = slurp(rec + "/console.modbus.log");
  CHECK(trace.rfind("# rise-hild modbus trace v1", 0) == 0);
  CHECK(trace.find(" fc=04 addr=0 count=18 ") != std::string::npos);
  CHECK(trace.find(" fc=16 addr=0 count=25 ") != std::string::npos);
  std::string out;
  INFO("logs in " << dir.path);
  CHECK(verify({"--panel", panel, "--record-dir", rec}, dir.path + "/verify.log", out) == 0);
  CHECK(out.rfind("pass: ", 0) == 0);
}

TEST_CASE("a live CANopen session recorded with --record verifies against its own PanelState log",
          "[integration][canopen]") {
  TempDir dir("rise-record-canopen");
  const std::string bus = "127.0.0.1:" + port_text(2) + "/can0";
  const std::string id = "corec" + std::to_string(::getpid());
  const std::string panel = kSource + "/panels/definitions/rise_console_canopen.yaml";
  record_live_session(panel, "socketcand://" + bus, {"--can", "socketcand+listen://" + bus}, id, dir.path,
                      kSource + "/tests/integration/canopen_script.txt");
  const std::string rec = dir.path + "/rec";
  const std::string log = slurp(rec + "/console.log");
  INFO("logs in " << dir.path);
  // What the bridge sent (T) and the node answered (R), in CiA 301's bytes.
  CHECK(log.find(" 000#8205 T") != std::string::npos);  // reset communication at open
  CHECK(log.find(" 705#00 R") != std::string::npos);    // boot-up
  CHECK(log.find(" 000#0105 T") != std::string::npos);  // start remote node
  CHECK(log.find(" 080# T") != std::string::npos);      // SYNC
  CHECK(log.find(" 705#7F R") != std::string::npos);    // pre-operational (@status fault)
  CHECK(log.find(" 205#") != std::string::npos);        // RPDO1: the LEDs and the display
  const auto states = read_states(rec + "/panel_state.lcmlog");
  const auto preop = std::find_if(states.begin(), states.end(), [](const rise_msgs::PanelState& s) {
    return s.failsafe_reason.find("node 5 pre-operational") != std::string::npos;
  });
  REQUIRE(preop != states.end());
  // Started again after the power cycle (the end is failsafe: the emulator is gone).
  CHECK(std::any_of(preop, states.end(), [](const rise_msgs::PanelState& s) { return !s.failsafe; }));
  std::string out;
  CHECK(verify({"--panel", panel, "--record-dir", rec}, dir.path + "/verify.log", out) == 0);
  CHECK(out.rfind("pass: " + std::to_string(states.size()) + " of " + std::to_string(states.size()), 0) == 0);
}

TEST_CASE("python-can's log reader reads every frame kind of a candump log we write as we read it", "[integration]") {
  if (!python_can_available()) {
    WARN("skipped: /usr/bin/python3 with python3-can (Debian) is not installed");
    return;
  }
  TempDir dir("rise-pycan-log");
  const std::string path = dir.path + "/console.log";
  {
    rise::hil::io::RecordingBus recorded(rise::hil::io::open_can_bus("mem://pycan_log"), path, "console");
    auto peer = rise::hil::io::open_can_bus("mem://pycan_log");
    std::vector<rise::hil::io::CanFrame> frames;
    frames.reserve(16);  // add() hands out pointers into it
    auto add = [&](uint32_t id, std::vector<uint8_t> data) {
      rise::hil::io::CanFrame f;
      f.id = id;
      f.len = static_cast<uint8_t>(data.size());
      std::copy(data.begin(), data.end(), f.data.begin());
      f.timestamp_us = 1'700'000'000'000'000 + static_cast<int64_t>(frames.size()) * 1001;
      frames.push_back(f);
      return &frames.back();
    };
    add(0x110, {0x57, 0x05, 0x00, 0xC0, 0x66, 0x66, 0x00, 0x00});
    add(0x7FF, {});
    frames.back().remote = true;
    frames.back().len = 4;
    add(0x18DAF110, {0x02, 0x10, 0x03})->extended = true;
    auto* fd = add(0x123, std::vector<uint8_t>(64, 0xA5));
    fd->fd = fd->brs = true;
    auto* esi = add(0x1ABCDEF0, std::vector<uint8_t>(12, 0x11));
    esi->fd = esi->esi = esi->extended = true;
    auto* state = add(0x004, {0, 0x10, 0, 0, 0, 0, 0, 0});  // CAN_ERR_CRTL: rx warning
    state->error = true;
    auto* bus_error = add(0x080, {0, 0, 0, 0, 0, 0, 0, 0});  // CAN_ERR_BUSERROR
    bus_error->error = true;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      if (i % 2) {
        REQUIRE(recorded.send(frames[i]) == rise::hil::io::IoStatus::Ok);
      } else {
        REQUIRE(peer->send(frames[i]) == rise::hil::io::IoStatus::Ok);
        rise::hil::io::CanFrame got;
        REQUIRE(recorded.receive(got, 1000) == rise::hil::io::IoStatus::Ok);
      }
    }
  }
  REQUIRE(rise::hil::io::read_can_log(path).size() == 7);
  check_python_can_reads(path, dir.path);
}

TEST_CASE("rise-hild plays a HID recording as its device (replay://), records the same reports, and verify passes",
          "[integration]") {
  TempDir dir("rise-hid-rerecord");
  const std::string panel = kSource + "/tests/data/replay/hid/pad.yaml";
  const std::string golden = kSource + "/tests/data/replay/hid/pad.hid";
  const std::string log = dir.path + "/rise-hild.log";
  ChildProcess hild({kBin + "/rise-hild", "--panel", panel, "--source", "replay://" + golden, "--id", "hidrec", "--lcm",
                     "memq://", "--status-every", "0.05", "--record", dir.path + "/rec"},
                    log);
  // The replay's end fails the pad safe for good after its re-plug: the status line says so.
  const std::regex gone("source pad: connected=false .* reconnects=1 ");
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (!std::regex_search(slurp(log), gone) && std::chrono::steady_clock::now() < deadline && hild.running())
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  INFO(slurp(log));
  REQUIRE(std::regex_search(slurp(log), gone));
  CHECK(hild.stop() == 0);
  CHECK(slurp(log).find("source 'pad': replaying replay://" + golden) != std::string::npos);
  std::string out;
  CHECK(verify({"--panel", panel, "--record-dir", dir.path + "/rec"}, dir.path + "/verify.log", out) == 0);
  CHECK(out.rfind("pass: ", 0) == 0);
  // The daemon read the golden's reports, byte for byte and in order, at the
  // golden's plugs (times are its own).
  auto reports = [](const std::string& path) {
    rise::hil::io::HidRecordingReader reader(path);
    std::vector<std::vector<uint8_t>> out;
    rise::hil::io::HidRecordingRecord r;
    while (reader.next(r))
      if (r.kind != rise::hil::io::HidRecordingRecord::Kind::Unplug) out.push_back(r.bytes);
    return out;
  };
  const auto expected = reports(golden);
  CHECK(expected.size() > 200);
  CHECK(reports(dir.path + "/rec/pad.hid") == expected);
}
