// Vector BLF and pcap/pcapng through CanLogReader, each checked against an
// independent reader of the same file: python-can's BLFReader (Debian's
// python3-can) and Wireshark's tshark.
#include <catch2/catch.hpp>

#include <pcap/pcap.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "hil/io/can_bus.hpp"
#include "hil/io/can_log.hpp"
#include "hil/io/replay_bus.hpp"

using namespace rise::hil::io;

namespace {

std::string data_file(const std::string& relative) {
  const char* root = std::getenv("RISE_TEST_DATA");
  if (root == nullptr) return {};
  const std::string path = std::string(root) + "/can/" + relative;
  return std::filesystem::exists(path) ? path : std::string{};
}

bool have(const char* check) { return std::system(check) == 0; }

#define REQUIRE_PEER(check, what)                     \
  if (!have(check)) {                                 \
    WARN("skipped: " what " is not installed");       \
    return;                                           \
  }

#define REQUIRE_DATA(path)                               \
  if ((path).empty()) {                                  \
    WARN("skipped: a file of RISE_TEST_DATA is absent"); \
    return;                                              \
  }

constexpr const char* kPythonCan = "/usr/bin/python3 -c 'import can' >/dev/null 2>&1";
constexpr const char* kTshark = "tshark -v >/dev/null 2>&1";

struct TempDir {
  std::filesystem::path dir = std::filesystem::temp_directory_path() /
                              ("rise_can_log_binary_" + std::to_string(::getpid()));
  TempDir() { std::filesystem::create_directories(dir); }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(dir, ignored);
  }
  std::string operator/(const std::string& name) const { return (dir / name).string(); }
};

std::string run(const std::string& cmd) {
  FILE* p = ::popen(cmd.c_str(), "r");
  REQUIRE(p != nullptr);
  std::string out;
  char buf[65536];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  REQUIRE(::pclose(p) == 0);
  return out;
}

std::string hex(const CanFrame& f) {
  if (f.remote || f.len == 0) return "-";
  std::string s;
  char b[3];
  for (unsigned i = 0; i < f.len; ++i) {
    std::snprintf(b, sizeof b, "%02x", f.data[i]);
    s += b;
  }
  return s;
}

const std::string kBlfTool = std::string(RISE_SOURCE_DIR) + "/tests/hil_io/python_can_blf.py";

// python-can's reading of a BLF, one line per frame (python_can_blf.py dump).
struct TheirFrame {
  uint32_t id = 0;
  int extended = 0, remote = 0, error = 0, fd = 0, brs = 0, esi = 0;
  long long time_us = 0;
  std::string data;
};

std::vector<TheirFrame> python_can_read(const std::string& blf) {
  // BLF's start time has no zone: python-can reads it in the local one, we as UTC.
  std::istringstream in(run("TZ=UTC /usr/bin/python3 " + kBlfTool + " dump '" + blf + "'"));
  std::vector<TheirFrame> frames;
  TheirFrame t;
  std::string id;
  while (in >> id >> t.extended >> t.remote >> t.error >> t.fd >> t.brs >> t.esi >> t.time_us >> t.data) {
    t.id = static_cast<uint32_t>(std::stoul(id, nullptr, 16));
    frames.push_back(t);
  }
  return frames;
}

// Every frame as python-can reads it, in order. Error frames: BLF carries
// Vector's error codes, not a SocketCAN class; we give id 0 and 8 zero bytes.
void check_same_as_python_can(const std::string& blf, size_t min_frames) {
  const auto theirs = python_can_read(blf);
  CanLogReader reader(blf);
  CHECK(reader.format() == CanLogFormat::VectorBlf);
  std::vector<CanLogRecord> ours;
  CanLogRecord r;
  while (reader.next(r)) ours.push_back(r);
  CHECK(reader.malformed_count() == 0);
  CHECK(reader.bytes_consumed() == reader.size_bytes());
  REQUIRE(ours.size() == theirs.size());
  REQUIRE(ours.size() >= min_frames);
  for (size_t i = 0; i < ours.size(); ++i) {
    const CanFrame& f = ours[i].frame;
    const TheirFrame& t = theirs[i];
    INFO(blf << " frame " << i);
    CHECK(f.error == (t.error != 0));
    CHECK(std::llabs(f.timestamp_us - t.time_us) <= 1);
    if (f.error) continue;
    CHECK(f.id == t.id);
    CHECK(f.extended == (t.extended != 0));
    CHECK(f.remote == (t.remote != 0));
    CHECK(f.fd == (t.fd != 0));
    CHECK(f.brs == (t.brs != 0));
    CHECK(f.esi == (t.esi != 0));
    CHECK(hex(f) == t.data);
    CHECK(is_well_formed(f));
  }
}

}  // namespace

TEST_CASE("BLF: python-can's own test file: its two frames are ill-formed, counted as malformed", "[hil_io][blf]") {
  const std::string blf = data_file("python-can/test_CanMessage.blf");
  REQUIRE_DATA(blf);
  REQUIRE_PEER(kPythonCan, "/usr/bin/python3 with python3-can (Debian)");
  // The file is filled with test patterns: both CAN_MESSAGE objects say id
  // 0x44444444 without the extended bit, an 11-bit frame with a 27-bit id.
  // python-can yields them as they stand; no bus can carry them, and our
  // ASC and TRC readers count such lines as malformed: so do we.
  const auto theirs = python_can_read(blf);
  REQUIRE(theirs.size() == 2);
  for (const auto& t : theirs) {
    CHECK(t.id == 0x4444444);
    CHECK(t.extended == 0);
    CHECK(t.data == "5566778899aabbcc");
  }
  CanLogReader reader(blf);
  CHECK(reader.format() == CanLogFormat::VectorBlf);
  CanLogRecord r;
  CHECK_FALSE(reader.next(r));
  CHECK(reader.malformed_count() == 2);
  CHECK(reader.malformed_lines() == std::vector<int>{1, 2});
  CHECK(reader.bytes_consumed() == reader.size_bytes());
  // With the id's high bits set as the extended flag, the same object reads.
  std::ifstream in(blf, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (size_t at : {0xd7u, 0x107u}) bytes[at] = static_cast<char>(0x84);
  TempDir tmp;
  const std::string fixed = tmp / "fixed.blf";
  std::ofstream(fixed, std::ios::binary) << bytes;
  check_same_as_python_can(fixed, 2);
  const auto records = read_can_log(fixed);
  REQUIRE(records.size() == 2);
  CHECK(records[0].frame.id == 0x4444444);
  CHECK(records[0].frame.extended);
  // Its DLC field says 0x33: a classic frame carries 8 bytes whatever it says.
  CHECK(records[0].frame.len == 8);
  CHECK(records[0].channel == "4369");  // BLF channels count from 1, as the file has them
  CHECK(records[0].frame.timestamp_us == 0x2222222222222222LL / 1000);
}

TEST_CASE("BLF written by python-can's BLFWriter from real logs: every frame as python-can and the source", "[hil_io][blf]") {
  REQUIRE_PEER(kPythonCan, "/usr/bin/python3 with python3-can (Debian)");
  TempDir tmp;
  struct Case { std::string source; const char* container; size_t min_frames; };
  // Small containers split objects across them; the ASC files bring CAN FD,
  // remote and error frames.
  const std::vector<Case> cases = {
      {data_file("ICSim/sample-can.log"), "", 6000},
      {data_file("python-can/issue_1256.asc"), "700", 1400},
      {data_file("python-can/test_CanFdMessage.asc"), "", 3},
      {data_file("python-can/logfile_errorframes.asc"), "100", 10},
  };
  for (const auto& c : cases) {
    REQUIRE_DATA(c.source);
    const std::string blf = tmp / (std::filesystem::path(c.source).filename().string() + ".blf");
    run("TZ=UTC /usr/bin/python3 " + kBlfTool + " write '" + c.source + "' '" + blf + "' " + c.container);
    check_same_as_python_can(blf, c.min_frames);
    // And the same frames as our reader of the source, at the same times:
    // the writer puts the first frame's time, to the ms, in the header.
    const auto source = read_can_log(c.source);
    const auto ours = read_can_log(blf);
    REQUIRE(ours.size() == source.size());
    const bool epoch = source[0].frame.timestamp_us > 631152000LL * 1000000;  // as python-can's writer tells it
    CHECK(std::llabs(ours[0].frame.timestamp_us - (epoch ? source[0].frame.timestamp_us : 0)) <= 500);
    for (size_t i = 0; i < ours.size(); ++i) {
      INFO(c.source << " frame " << i);
      CHECK(same_content(ours[i].frame, source[i].frame));
      CHECK(std::llabs((ours[i].frame.timestamp_us - ours[0].frame.timestamp_us) -
                       (source[i].frame.timestamp_us - source[0].frame.timestamp_us)) <= 1);
    }
  }
}

TEST_CASE("BLF objects python-can's writer never makes: CAN_FD_MESSAGE_64, CAN_MESSAGE2 with a v2 header in 10 us units", "[hil_io][blf]") {
  REQUIRE_PEER(kPythonCan, "/usr/bin/python3 with python3-can (Debian)");
  TempDir tmp;
  const std::string blf = tmp / "crafted.blf";
  run("TZ=UTC /usr/bin/python3 " + kBlfTool + " craft '" + blf + "'");
  check_same_as_python_can(blf, 6);
  const auto r = read_can_log(blf);
  REQUIRE(r.size() == 6);
  constexpr int64_t kStart = 1714655655678000;  // the header's 2024-05-02 13:14:15.678
  CHECK(r[0].frame.timestamp_us == kStart + 1);  // 1000 ns
  CHECK(r[0].frame.fd);
  CHECK(r[0].frame.brs);
  CHECK(r[0].frame.len == 64);
  CHECK(r[0].tx);
  CHECK(r[1].frame.esi);
  CHECK_FALSE(r[1].tx);
  CHECK(r[2].frame.remote);
  CHECK(r[2].frame.timestamp_us == kStart + 3450);  // 345 × 10 us
  CHECK(r[2].channel == "3");
  CHECK(r[4].frame.fd);
  CHECK(r[4].frame.len == 12);
  CHECK(r[5].frame.error);
}

TEST_CASE("BLF cut or corrupted anywhere: counted as malformed, never thrown, frames before it kept", "[hil_io][blf]") {
  const std::string source = data_file("python-can/issue_1256.asc");
  REQUIRE_DATA(source);
  REQUIRE_PEER(kPythonCan, "/usr/bin/python3 with python3-can (Debian)");
  TempDir tmp;
  const std::string blf = tmp / "whole.blf";
  run("TZ=UTC /usr/bin/python3 " + kBlfTool + " write '" + source + "' '" + blf + "' 2000");
  const auto whole = read_can_log(blf);
  std::ifstream in(blf, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string cut = tmp / "cut.blf";
  size_t cuts_with_malformed = 0;
  for (size_t at = 200; at < bytes.size(); at += 211) {
    std::ofstream(cut, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(at));
    CanLogReader reader(cut);
    std::vector<CanLogRecord> got;
    CanLogRecord r;
    while (reader.next(r)) got.push_back(r);
    INFO("cut at " << at);
    REQUIRE(got.size() <= whole.size());
    REQUIRE(reader.bytes_consumed() <= reader.size_bytes());
    for (size_t i = 0; i < got.size(); ++i) REQUIRE(same_content(got[i].frame, whole[i].frame));
    cuts_with_malformed += reader.malformed_count() > 0;
  }
  CHECK(cuts_with_malformed > 0);
  // Bytes overwritten inside the compressed data and in object headers.
  const std::string bad = tmp / "bad.blf";
  for (size_t at = 150; at < bytes.size(); at += 97) {
    std::string copy = bytes;
    copy[at] = static_cast<char>(copy[at] ^ 0x5A);
    copy[at + 1 < copy.size() ? at + 1 : at] = 'L';
    std::ofstream(bad, std::ios::binary | std::ios::trunc) << copy;
    CanLogReader reader(bad);
    CanLogRecord r;
    size_t n = 0;
    while (reader.next(r)) ++n;
    CHECK(n <= whole.size() + 1);
  }
  // A file that is only the magic.
  std::ofstream(bad, std::ios::binary | std::ios::trunc) << "LOGG";
  CHECK_THROWS_WITH(CanLogReader(bad), Catch::Contains("BLF"));
  // A header that claims 144 bytes of a 130-byte file: read as far as the
  // file goes (tests/fuzz/logs_fuzz.cpp found the progress past the end).
  std::string claims(130, '\0');
  claims.replace(0, 8, std::string("LOGG\x90\0\0\0", 8));
  std::ofstream(bad, std::ios::binary | std::ios::trunc) << claims;
  CanLogReader reader(bad);
  CanLogRecord r;
  while (reader.next(r)) {
  }
  CHECK(reader.bytes_consumed() <= reader.size_bytes());
}

namespace {

// A pcap as libpcap's own writer makes it: link type 227 (the CAN id in
// network byte order), or Linux cooked SLL2 (the id in host order, as a
// real tcpdump -i any capture has it) with a non-CAN packet between.
void write_pcap(const std::string& path, int link, const std::vector<CanLogRecord>& records) {
  pcap_t* dead = pcap_open_dead(link, 65535);
  REQUIRE(dead != nullptr);
  pcap_dumper_t* dump = pcap_dump_open(dead, path.c_str());
  REQUIRE(dump != nullptr);
  for (const auto& rec : records) {
    const CanFrame& f = rec.frame;
    std::vector<u_char> p;
    const uint16_t protocol = f.fd ? 0x000D : 0x000C;
    if (link == DLT_LINUX_SLL2) {
      p = {static_cast<u_char>(protocol >> 8), static_cast<u_char>(protocol), 0, 0, 0, 0, 0, 3,
           0x01, 0x18, static_cast<u_char>(rec.tx ? 4 : 0), 0, 0, 0, 0, 0, 0, 0, 0, 0};
    }
    const uint32_t id = f.id | (f.extended ? 0x80000000u : 0) | (f.remote ? 0x40000000u : 0) | (f.error ? 0x20000000u : 0);
    const u_char flags = static_cast<u_char>((f.brs ? 1 : 0) | (f.esi ? 2 : 0) | (f.fd ? 4 : 0));
    u_char head[8] = {static_cast<u_char>(id >> 24), static_cast<u_char>(id >> 16), static_cast<u_char>(id >> 8),
                      static_cast<u_char>(id), f.len, flags, 0, 0};
    if (link == DLT_LINUX_SLL2) std::reverse(head, head + 4);
    p.insert(p.end(), head, head + 8);
    p.insert(p.end(), f.data.begin(), f.data.begin() + (f.fd ? 64 : 8));
    pcap_pkthdr h{};
    h.ts.tv_sec = f.timestamp_us / 1000000;
    h.ts.tv_usec = f.timestamp_us % 1000000;
    h.caplen = h.len = static_cast<bpf_u_int32>(p.size());
    pcap_dump(reinterpret_cast<u_char*>(dump), &h, p.data());
    if (link == DLT_LINUX_SLL2) {  // an IPv4 packet that is no CAN frame
      std::vector<u_char> ip = {0x08, 0x00, 0, 0, 0, 0, 0, 1, 0x03, 0x04, 0, 6, 1, 2, 3, 4, 5, 6, 0, 0};
      ip.resize(48);
      h.caplen = h.len = static_cast<bpf_u_int32>(ip.size());
      pcap_dump(reinterpret_cast<u_char*>(dump), &h, ip.data());
    }
  }
  pcap_dump_close(dump);
  pcap_close(dead);
}

// Frames from a real log plus every kind the format carries.
std::vector<CanLogRecord> pcap_frames(const std::string& log) {
  auto records = read_can_log(log);
  CanLogRecord r = records.back();
  const auto add = [&](auto change) {
    r.frame = CanFrame{};
    r.frame.timestamp_us = records.back().frame.timestamp_us + 1234;
    change(r.frame);
    records.push_back(r);
  };
  add([](CanFrame& f) { f.id = 0x18EBFF00; f.extended = true; f.len = 8; f.data = {1, 2, 3, 4, 5, 6, 7, 8}; });
  add([](CanFrame& f) { f.id = 0x7FF; f.remote = true; f.len = 4; });
  add([](CanFrame& f) { f.id = 0x123; f.fd = true; f.brs = true; f.len = 48; f.data.fill(0xA5); });
  add([](CanFrame& f) { f.id = 0x1ABCDE; f.extended = true; f.fd = true; f.esi = true; f.len = 12; f.data[11] = 9; });
  add([](CanFrame& f) { f.id = 0x4; f.error = true; f.len = 8; f.data[1] = 0x10; });
  return records;
}

// tshark's reading of each CAN frame, its fields by name.
struct TsharkFrame {
  std::string id, extended, remote, error, len, brs, esi, data;
};

std::vector<TsharkFrame> tshark_read(const std::string& path) {
  const std::string out = run("tshark -r '" + path + "' -Y 'can || canfd' -T fields -e can.id -e can.flags.xtd "
                              "-e can.flags.rtr -e can.flags.err -e can.len -e canfd.flags.brs -e canfd.flags.esi "
                              "-e data.data 2>/dev/null");
  std::vector<TsharkFrame> frames;
  std::istringstream in(out);
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> f;
    std::istringstream fields(line);
    for (std::string v; std::getline(fields, v, '\t');) f.push_back(v);
    f.resize(8);
    frames.push_back({f[0], f[1], f[2], f[3], f[4], f[5], f[6], f[7]});
  }
  return frames;
}

// tshark names an error frame by its flag only, shows FD frames without
// the remote and error flags, and the bytes a remote frame's packet holds.
void check_as_tshark(const CanFrame& f, const TsharkFrame& t) {
  const auto bit = [](bool v) { return std::string(v ? "1" : "0"); };
  CHECK(bit(f.error) == (t.error.empty() ? "0" : t.error));
  if (f.error) return;
  CHECK(std::to_string(f.id) == t.id);
  CHECK(bit(f.extended) == t.extended);
  CHECK(std::to_string(f.len) == t.len);
  CHECK(f.fd == !t.brs.empty());
  if (f.fd) {
    CHECK(bit(f.brs) == t.brs);
    CHECK(bit(f.esi) == t.esi);
  } else {
    CHECK(bit(f.remote) == t.remote);
  }
  if (!f.remote) CHECK((f.len == 0 ? "" : hex(f)) == t.data);
}

}  // namespace

TEST_CASE("pcap and pcapng of SocketCAN: every frame as tshark and the source log read it", "[hil_io][pcap]") {
  const std::string log = data_file("CANBUSlogs-yaris09/accellog.log");
  REQUIRE_DATA(log);
  REQUIRE_PEER(kTshark, "tshark (Debian)");
  TempDir tmp;
  const auto frames = pcap_frames(log);
  for (const int link : {227, DLT_LINUX_SLL2}) {
    const std::string pcap = tmp / ("frames_" + std::to_string(link) + ".pcap");
    write_pcap(pcap, link, frames);
    const std::string pcapng = tmp / ("frames_" + std::to_string(link) + ".pcapng");
    run("editcap -F pcapng '" + pcap + "' '" + pcapng + "'");
    for (const auto& path : {pcap, pcapng}) {
      INFO(path);
      CanLogReader reader(path);
      CHECK(reader.format() == (path == pcap ? CanLogFormat::Pcap : CanLogFormat::Pcapng));
      std::vector<CanLogRecord> ours;
      CanLogRecord r;
      while (reader.next(r)) ours.push_back(r);
      CHECK(reader.malformed_count() == 0);
      CHECK(reader.bytes_consumed() == reader.size_bytes());
      REQUIRE(ours.size() == frames.size());
      const auto theirs = tshark_read(path);
      REQUIRE(theirs.size() == frames.size());
      for (size_t i = 0; i < ours.size(); ++i) {
        INFO("frame " << i);
        CHECK(same_content(ours[i].frame, frames[i].frame));
        CHECK(ours[i].frame.timestamp_us == frames[i].frame.timestamp_us);
        CHECK(ours[i].tx == (link == DLT_LINUX_SLL2 && frames[i].tx));
        check_as_tshark(ours[i].frame, theirs[i]);
      }
      reader.rewind();
      CHECK(reader.next(r));
      CHECK(same_content(r.frame, frames[0].frame));
    }
  }
}

TEST_CASE("pcap: a cut capture ends with one malformed record; other link types are refused", "[hil_io][pcap]") {
  const std::string log = data_file("CANBUSlogs-yaris09/accellog.log");
  REQUIRE_DATA(log);
  TempDir tmp;
  const auto frames = pcap_frames(log);
  const std::string pcap = tmp / "whole.pcap";
  write_pcap(pcap, 227, frames);
  const auto size = std::filesystem::file_size(pcap);
  std::filesystem::resize_file(pcap, size - 5);
  CanLogReader reader(pcap);
  CanLogRecord r;
  size_t n = 0;
  while (reader.next(r)) ++n;
  CHECK(n == frames.size() - 1);
  CHECK(reader.malformed_count() == 1);
  CHECK_FALSE(reader.next(r));
  CHECK(reader.malformed_count() == 1);

  pcap_t* dead = pcap_open_dead(DLT_EN10MB, 65535);
  const std::string ether = tmp / "ether.pcap";
  pcap_dumper_t* dump = pcap_dump_open(dead, ether.c_str());
  pcap_dump_close(dump);
  pcap_close(dead);
  CHECK_THROWS_WITH(CanLogReader(ether), Catch::Contains("link type 1 (EN10MB) is not SocketCAN"));
}

TEST_CASE("replay:// plays a BLF and a pcapng like the log they were made from", "[hil_io][blf][pcap]") {
  const std::string log = data_file("CANBUSlogs-yaris09/accellog.log");
  REQUIRE_DATA(log);
  REQUIRE_PEER(kPythonCan, "/usr/bin/python3 with python3-can (Debian)");
  REQUIRE_PEER("editcap -v >/dev/null 2>&1", "editcap (Debian's wireshark-common, with tshark)");
  TempDir tmp;
  const std::string blf = tmp / "accel.blf";
  run("TZ=UTC /usr/bin/python3 " + kBlfTool + " write '" + log + "' '" + blf + "'");
  const std::string pcap = tmp / "accel.pcap";
  const std::string pcapng = tmp / "accel.pcapng";
  write_pcap(pcap, 227, read_can_log(log));
  run("editcap -F pcapng '" + pcap + "' '" + pcapng + "'");
  const auto source = read_can_log(log);
  for (const auto& file : {blf, pcapng}) {
    INFO(file);
    // Twice through (loop=1), only the ids 0x2C1 and 0x3B3 kept.
    auto bus = open_can_bus("replay://" + file + "?fast=1&loop=1&ids=2C1,3B3");
    auto* replay = dynamic_cast<ReplayBus*>(bus.get());
    REQUIRE(replay != nullptr);
    std::vector<CanFrame> played;
    CanFrame f;
    for (int i = 0; i < 100'000; ++i) {
      const IoStatus st = bus->receive(f, 1000);
      if (st == IoStatus::Disconnected) break;
      if (st == IoStatus::Ok) played.push_back(f);
    }
    std::vector<CanFrame> expected;
    for (int pass = 0; pass < 2; ++pass)
      for (const auto& r : source)
        if (r.frame.id == 0x2C1 || r.frame.id == 0x3B3) expected.push_back(r.frame);
    REQUIRE(expected.size() > 100);
    REQUIRE(played.size() == expected.size());
    for (size_t i = 0; i < played.size(); ++i) CHECK(same_content(played[i], expected[i]));
    CHECK(replay->loops_done() == 1);
  }
}
