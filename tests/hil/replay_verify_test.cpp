// Verified replay on the recorded sessions in tests/data/replay (made by
// make_goldens.sh from live emulator → rise-hild runs): the captures replay
// to their golden PanelState streams, one changed byte fails naming the
// first difference, and injected corruption has the PanelState effect the
// safety rules promise.

#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "firmware_protocol/console_can.hpp"
#include "hil/io/candump_log.hpp"
#include "hil/replay_verify.hpp"
#include "msgs/failsafe.hpp"
#include "panels/panel_definition.hpp"

using namespace rise::hil;
namespace fp = rise::firmware_protocol;

namespace {
const std::string kData = std::string(RISE_SOURCE_DIR) + "/tests/data/replay";
const std::string kPanels = std::string(RISE_SOURCE_DIR) + "/panels/definitions";

std::vector<std::string> read_lines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

void write_lines(const std::string& path, const std::vector<std::string>& lines) {
  std::ofstream out(path);
  for (const auto& l : lines) out << l << "\n";
}

int64_t line_time(const std::string& line) {
  return rise::hil::io::parse_log_time(line, nullptr).value_or(-1);
}

// A scratch copy of one recorded session whose files a test may change.
struct SessionCopy {
  std::string dir;
  explicit SessionCopy(const std::string& session) {
    static int n = 0;
    dir = std::filesystem::temp_directory_path() /
          ("rise-replay-" + std::to_string(::getpid()) + "-" + std::to_string(n++));
    std::filesystem::create_directories(dir);
    for (const auto& e : std::filesystem::directory_iterator(kData + "/" + session))
      std::filesystem::copy_file(e.path(), dir + "/" + e.path().filename().string());
  }
  ~SessionCopy() { std::filesystem::remove_all(dir); }
  /// Index of the first line at or after `from_s` seconds into the file that `pred` accepts.
  std::size_t find(const std::vector<std::string>& lines, double from_s,
                   const std::function<bool(const std::string&)>& pred) const {
    int64_t start = -1;
    for (std::size_t i = 0; i < lines.size(); ++i) {
      const int64_t t = line_time(lines[i]);
      if (t < 0) continue;
      if (start < 0) start = t;
      if (static_cast<double>(t - start) * 1e-6 >= from_s && pred(lines[i])) return i;
    }
    FAIL("no line matches");
    return 0;
  }
};

// "(t) console 130#AABBCCDDEEFF0011 R" → its frame.
rise::hil::io::CanFrame frame_of(const std::string& line) { return rise::hil::io::parse_candump_line(line).record.frame; }

std::string with_frame(const std::string& line, const rise::hil::io::CanFrame& f) {
  return rise::hil::io::format_candump_line(f, rise::hil::io::parse_candump_line(line).record.interface,
                                       rise::hil::io::CandumpDirection::Received);
}

bool received(const std::string& line, uint32_t id) {
  const auto p = rise::hil::io::parse_candump_line(line);
  return p.ok() && !p.record.tx && p.record.frame.id == id;
}

constexpr uint32_t kAxes0 = 0x110;    // node 0: drive_x, drive_y, arm_x
constexpr uint32_t kButtons = 0x130;

bool is_axes0(const std::string& l) { return received(l, kAxes0); }
bool is_register_poll(const std::string& l) {
  return l.find(" fc=04 ") != std::string::npos && l.find(" ok ") != std::string::npos;
}

// A copy of a recorded session with one line of `file` changed: the first
// from 0.5 s on that `pred` accepts, rewritten by `change`.
struct ChangedSession {
  rise::panels::PanelDefinition def;
  SessionCopy copy;
  std::size_t line = 0;  // 1-based
  int64_t changed_us = 0;
  ChangedSession(const std::string& session, const std::string& panel, const std::string& file,
                 const std::function<bool(const std::string&)>& pred, const std::function<void(std::string&)>& change)
      : def(rise::panels::load_panel_definition(kPanels + "/" + panel)), copy(session) {
    auto lines = read_lines(copy.dir + "/" + file);
    const std::size_t i = copy.find(lines, 0.5, pred);
    change(lines[i]);
    write_lines(copy.dir + "/" + file, lines);
    line = i + 1;
    changed_us = line_time(lines[i]);
  }
  VerifyReport verify() const {
    return verify_replay(def, captures_in(def, copy.dir), read_panel_state_log(copy.dir + "/panel_state.lcmlog").messages);
  }
};

}  // namespace

TEST_CASE("the recorded CAN, Modbus and split sessions replay to their golden PanelState streams", "[hil]") {
  const auto [session, panel] = GENERATE(table<std::string, std::string>({
      {"can", "rise_console.yaml"},
      {"modbus", "rise_console_modbus.yaml"},
      {"split", "rise_console_split.yaml"},
  }));
  INFO(session);
  const auto def = rise::panels::load_panel_definition(kPanels + "/" + panel);
  const PanelStateLog golden = read_panel_state_log(kData + "/" + session + "/panel_state.lcmlog");
  // The session holds what it is meant to check: driving, the dead-man let
  // go, the bad CRCs, the console's silence.
  bool driving = false, released = false, crc = false, stale = false;
  for (const auto& m : golden.messages) {
    driving = driving || (!m.failsafe && m.deadman && m.axes[1].value > 0.5f);
    released = released || (!m.failsafe && !m.deadman);
    crc = crc || rise::msgs::has(m.failsafe_causes, rise::msgs::FailsafeCause::ProtectionFailed);
    stale = stale || rise::msgs::has(m.failsafe_causes, rise::msgs::FailsafeCause::SourceStale);
  }
  CHECK(driving);
  CHECK(released);
  CHECK(crc);
  CHECK(stale);

  const VerifyReport report = verify_replay(def, captures_in(def, kData + "/" + session), golden.messages);
  if (report.difference) INFO(describe(*report.difference));
  CHECK(report.passed());
  CHECK(report.messages == golden.messages.size());
  CHECK(report.messages > 150);
  CHECK(report.records > 150);
}

TEST_CASE("one changed byte in a capture fails the verification at the first message after it, naming the field",
          "[hil]") {
  SECTION("an axis byte of a CAN frame: the CRC fails") {
    const ChangedSession changed("can", "rise_console.yaml", "console.log", is_axes0, [](std::string& l) {
      auto f = frame_of(l);
      f.data[5] ^= 0x40;  // drive_y's high byte
      l = with_frame(l, f);
    });
    const VerifyReport report = changed.verify();
    REQUIRE_FALSE(report.passed());
    const VerifyDifference& d = *report.difference;
    INFO(describe(d));
    // The next three frames came within 4 ms and healed the failed check
    // before the next publish: the CRC count is what differs, in the first
    // message after the frame (the next 10 ms tick).
    CHECK(d.field == "console.crc_errors");
    CHECK(d.expected == "0");
    CHECK(d.got == "1");
    CHECK(d.also.empty());
    CHECK(d.utime > changed.changed_us);
    CHECK(d.utime <= changed.changed_us + 10'000 + 2'000);
    CHECK(d.time_s == Approx(static_cast<double>(d.utime - report.start_us) * 1e-6).margin(1e-9));
    CHECK(describe(d) == "t=" + std::to_string(d.time_s) + " s (message " + std::to_string(d.message) +
                             ", seq " + std::to_string(d.seq) + "): console.crc_errors: expected 0, got 1");
  }
  SECTION("the same byte with the CRC made good again: the axis itself differs") {
    const ChangedSession changed("can", "rise_console.yaml", "console.log", is_axes0, [](std::string& l) {
      auto f = frame_of(l);
      f.data[5] ^= 0x40;
      f.data[0] = fp::frame_crc(kAxes0, std::span<const uint8_t, fp::kFrameLength>(f.data.data(), fp::kFrameLength));
      l = with_frame(l, f);
    });
    const VerifyReport report = changed.verify();
    REQUIRE_FALSE(report.passed());
    INFO(describe(*report.difference));
    CHECK(report.difference->field == "drive_y");
    CHECK(report.difference->also.empty());
    CHECK(report.difference->utime > changed.changed_us);
  }
  SECTION("an axis digit of a Modbus input register: the map's CRC fails, the panel goes failsafe") {
    const ChangedSession changed("modbus", "rise_console_modbus.yaml", "console.modbus.log", is_register_poll,
                                 [](std::string& l) {
                                   // Register 1 (axis.1, drive_y) is the second value after "ok".
                                   const std::size_t at = l.find(" ok ") + 4 + 5;
                                   l[at] = l[at] == '0' ? '1' : '0';
                                 });
    const VerifyReport report = changed.verify();
    REQUIRE_FALSE(report.passed());
    INFO(describe(*report.difference));
    CHECK(report.difference->field == "failsafe");
    CHECK(report.difference->got == "true (\"console: protection check failed\")");
    CHECK(report.difference->utime > changed.changed_us);
  }
}

TEST_CASE("injected corruption in a CAN capture fails the panel safe with the reason until recovery_frames good "
          "frames",
          "[hil]") {
  const auto def = rise::panels::load_panel_definition(kPanels + "/rise_console.yaml");
  SessionCopy copy("can");
  auto lines = read_lines(copy.dir + "/console.log");
  // A Buttons frame while driving (dead-man held, no failsafe).
  std::size_t i = copy.find(lines, 0.5, [](const std::string& l) { return received(l, kButtons); });
  const int64_t t = line_time(lines[i]);
  std::size_t counter_kind = 0;
  SECTION("a bad CRC") {
    auto f = frame_of(lines[i]);
    f.data[0] ^= 0x01;
    lines[i] = with_frame(lines[i], f);
    counter_kind = static_cast<std::size_t>(fp::DecodeError::BadCrc);
  }
  SECTION("a repeated alive counter: the frame again, 1 ms later") {
    auto f = frame_of(lines[i]);
    f.timestamp_us += 1000;
    // In time order: after the frames of the same cycle.
    std::size_t at = i + 1;
    while (at < lines.size() && line_time(lines[at]) <= f.timestamp_us) ++at;
    lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(at), with_frame(lines[i], f));
    i = at;  // the repeat is the corrupt one
    counter_kind = static_cast<std::size_t>(fp::DecodeError::RepeatedCounter);
  }
  SECTION("a truncated line: the frame cut after its seventh byte") {
    lines[i] = lines[i].substr(0, lines[i].find('#') + 1 + 14) + " R";
    counter_kind = static_cast<std::size_t>(fp::DecodeError::BadLength);
  }
  write_lines(copy.dir + "/console.log", lines);
  const int64_t corrupt_us = line_time(lines[i]);

  CaptureReplay replay(def, captures_in(def, copy.dir));
  replay.advance_to(t - 1);
  const PanelSnapshot before = replay.mapper().preview(t - 1);
  REQUIRE_FALSE(before.failsafe);
  REQUIRE(before.deadman);
  replay.advance_to(corrupt_us);
  const PanelSnapshot hit = replay.mapper().preview(corrupt_us);
  CHECK(hit.failsafe);
  CHECK(hit.failsafe_reason == "console: protection check failed");
  CHECK_FALSE(hit.deadman);
  CHECK(hit.sources[0].errors[counter_kind] == before.sources[0].errors[counter_kind] + 1);
  // Every motion control is at its safe value.
  for (std::size_t c = 0; c < def.controls.size(); ++c)
    if (def.controls[c].motion) CHECK(hit.controls[c].forced_safe);

  // Failsafe through recovery_frames − 1 valid frames, healthy at the recovery_frames-th.
  const uint32_t recovery = def.sources[0].recovery_frames;
  REQUIRE(recovery == 3);
  for (uint32_t k = 1; k <= recovery; ++k) {
    const int64_t next = *replay.next_time_us();
    replay.apply_next();
    const PanelSnapshot s = replay.mapper().preview(next);
    INFO("valid frame " << k << " after the corrupt one");
    CHECK(s.failsafe == (k < recovery));
  }
}

TEST_CASE("injected corruption in a Modbus capture: a bad block CRC fails safe, a repeated alive counter only "
          "counts",
          "[hil]") {
  const auto def = rise::panels::load_panel_definition(kPanels + "/rise_console_modbus.yaml");
  SessionCopy copy("modbus");
  const std::string file = copy.dir + "/console.modbus.log";
  auto lines = read_lines(file);
  const std::size_t i = copy.find(lines, 0.5, is_register_poll);
  const std::size_t previous = [&] {
    for (std::size_t k = i; k-- > 0;)
      if (is_register_poll(lines[k])) return k;
    return i;
  }();
  REQUIRE(previous < i);
  // The poll completes with the discrete inputs on the next line.
  const int64_t t = line_time(lines[i]);
  bool expect_failsafe = false;
  SECTION("a register changed: the map's CRC fails") {
    const std::size_t at = lines[i].find(" ok ") + 4;
    lines[i][at] = lines[i][at] == '0' ? '1' : '0';
    expect_failsafe = true;
  }
  SECTION("the previous block served again: the same alive counter") {
    lines[i] = lines[i].substr(0, lines[i].find(" ok ")) + lines[previous].substr(lines[previous].find(" ok "));
  }
  write_lines(file, lines);

  CaptureReplay replay(def, captures_in(def, copy.dir));
  replay.advance_to(t - 1);
  const PanelSnapshot before = replay.mapper().preview(t - 1);
  REQUIRE_FALSE(before.failsafe);
  const int64_t answered = *replay.next_time_us();  // the poll's discrete inputs
  replay.apply_next();
  const PanelSnapshot hit = replay.mapper().preview(answered);
  const auto& e = hit.sources[0].errors;
  const auto& b = before.sources[0].errors;
  if (expect_failsafe) {
    CHECK(hit.failsafe);
    CHECK(hit.failsafe_reason == "console: protection check failed");
    CHECK(e[static_cast<std::size_t>(fp::DecodeError::BadCrc)] == b[static_cast<std::size_t>(fp::DecodeError::BadCrc)] + 1);
  } else {
    // No new data is no fault: the source's age (timeout_ms) judges it.
    CHECK_FALSE(hit.failsafe);
    CHECK(e[static_cast<std::size_t>(fp::DecodeError::RepeatedCounter)] ==
          b[static_cast<std::size_t>(fp::DecodeError::RepeatedCounter)] + 1);
  }
}

TEST_CASE("a capture line cut short is refused with its file and line", "[hil]") {
  SECTION("CAN: a frame cut inside a byte") {
    const ChangedSession cut("can", "rise_console.yaml", "console.log", is_axes0,
                             [](std::string& l) { l = l.substr(0, l.find('#') + 6); });
    CHECK_THROWS_WITH(cut.verify(), Catch::Contains("console.log:" + std::to_string(cut.line) +
                                                    ": not a candump frame line"));
  }
  SECTION("Modbus: a poll with a register missing") {
    const ChangedSession cut("modbus", "rise_console_modbus.yaml", "console.modbus.log", is_register_poll,
                             [](std::string& l) { l = l.substr(0, l.size() - 5); });
    CHECK_THROWS_WITH(cut.verify(), Catch::Contains("console.modbus.log:" + std::to_string(cut.line) +
                                                    ": count=18 but 17 registers"));
  }
}

TEST_CASE("a golden message matches the replayed state only within the time tolerance", "[hil]") {
  const auto def = rise::panels::load_panel_definition(kPanels + "/rise_console.yaml");
  auto golden = read_panel_state_log(kData + "/can/panel_state.lcmlog").messages;
  // The message where the dead-man is let go, moved 30 ms early: the replayed
  // panel then still has it held.
  std::size_t k = 1;
  while (k < golden.size() && !(golden[k - 1].deadman && !golden[k].deadman && !golden[k].failsafe)) ++k;
  REQUIRE(k < golden.size());
  golden[k].utime -= 30'000;
  std::vector<rise_msgs::PanelState> head(golden.begin(), golden.begin() + static_cast<std::ptrdiff_t>(k) + 1);
  VerifySettings settings;
  const VerifyReport strict = verify_replay(def, captures_in(def, kData + "/can"), head, settings);
  REQUIRE_FALSE(strict.passed());
  CHECK(strict.difference->message == k);
  CHECK(strict.difference->field == "deadman");
  settings.time_tolerance_us = 40'000;
  const VerifyReport loose = verify_replay(def, captures_in(def, kData + "/can"), head, settings);
  CHECK(loose.passed());
}

TEST_CASE("captures are matched to sources by their file names and refused for the wrong protocol", "[hil]") {
  const auto split = rise::panels::load_panel_definition(kPanels + "/rise_console_split.yaml");
  CHECK(capture_for(split, kData + "/split/sticks.log").source == 0);
  CHECK(capture_for(split, kData + "/split/buttons.modbus.log").source == 1);
  CHECK(capture_for(split, "buttons=" + kData + "/split/buttons.modbus.log").source == 1);
  CHECK_THROWS_WITH(capture_for(split, kData + "/can/console.log"), Catch::Contains("no source of"));
  CHECK_THROWS_WITH(capture_for(split, "sticks=" + kData + "/split/buttons.modbus.log"),
                    Catch::Contains("speaks rise-can-v1 but the file is a Modbus trace"));
  const auto can = rise::panels::load_panel_definition(kPanels + "/rise_console.yaml");
  CHECK_THROWS_WITH(verify_replay(can, captures_in(can, kData + "/can"),
                                  read_panel_state_log(kData + "/modbus/panel_state.lcmlog").messages),
                    Catch::Contains("of panel 'rise-console-modbus'"));
}
