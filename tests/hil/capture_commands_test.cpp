// rise-hild on captures: `modbus decode` on Zeek's real Modbus/TCP traces,
// and `dbc decode` on the same car capture as candump, Vector BLF (written by
// python-can) and pcap (written by libpcap): the same frames decode alike.

#include <catch2/catch.hpp>

#include <pcap/pcap.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "hil/io/can_log.hpp"
#include "process/child_process.hpp"

namespace {

std::string data_file(const std::string& relative) {
  const char* root = std::getenv("RISE_TEST_DATA");
  if (root == nullptr) return {};
  const std::string path = std::string(root) + "/" + relative;
  return std::filesystem::exists(path) ? path : std::string{};
}

#define REQUIRE_DATA(path)                               \
  if ((path).empty()) {                                  \
    WARN("skipped: a file of RISE_TEST_DATA is absent"); \
    return;                                              \
  }

struct Run {
  int rc = -1;
  std::string out;
};

// rise-hild ARGS, its stdout and stderr together.
Run hild(const std::vector<std::string>& args, const std::string& dir) {
  std::vector<std::string> argv = {std::string(RISE_BINARY_DIR) + "/bin/rise-hild"};
  argv.insert(argv.end(), args.begin(), args.end());
  static int runs = 0;
  const std::string log = dir + "/out" + std::to_string(++runs) + ".txt";
  rise::process::ChildProcess p(argv, log);
  Run r;
  r.rc = p.wait_for(60000);
  std::ifstream in(log);
  r.out.assign(std::istreambuf_iterator<char>(in), {});
  return r;
}

struct TempDir {
  std::string path = std::filesystem::temp_directory_path() / ("rise_capture_cmd_" + std::to_string(::getpid()));
  TempDir() { std::filesystem::create_directories(path); }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
};

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// The whitespace-separated fields of a table row.
std::vector<std::string> fields(const std::string& row) {
  std::vector<std::string> f;
  std::istringstream in(row);
  for (std::string v; in >> v;) f.push_back(v);
  return f;
}

// The frames of a CAN log as a pcap of link type 227, written by libpcap.
void write_pcap(const std::string& log, const std::string& pcap) {
  pcap_t* dead = pcap_open_dead(227, 65535);
  pcap_dumper_t* dump = pcap_dump_open(dead, pcap.c_str());
  REQUIRE(dump != nullptr);
  for (const auto& rec : rise::hil::io::read_can_log(log)) {
    const auto& f = rec.frame;
    const uint32_t id = f.id | (f.extended ? 0x80000000u : 0);
    std::vector<u_char> p = {static_cast<u_char>(id >> 24), static_cast<u_char>(id >> 16), static_cast<u_char>(id >> 8),
                             static_cast<u_char>(id), f.len, 0, 0, 0};
    p.insert(p.end(), f.data.begin(), f.data.begin() + 8);
    pcap_pkthdr h{};
    h.ts.tv_sec = f.timestamp_us / 1000000;
    h.ts.tv_usec = f.timestamp_us % 1000000;
    h.caplen = h.len = static_cast<bpf_u_int32>(p.size());
    pcap_dump(reinterpret_cast<u_char*>(dump), &h, p.data());
  }
  pcap_dump_close(dump);
  pcap_close(dead);
}

}  // namespace

TEST_CASE("rise-hild modbus decode prints the transactions of a real capture with their timing", "[hil][modbus]") {
  const std::string small = data_file("modbus/zeek/modbusSmall.pcap");
  const std::string sics = data_file("modbus/zeek/4SICS-GeekLounge-151022-min.pcap");
  REQUIRE_DATA(small);
  REQUIRE_DATA(sics);
  TempDir tmp;
  const Run r = hild({"modbus", "decode", small}, tmp.path);
  REQUIRE(r.rc == 0);
  const auto lines = lines_of(r.out);
  REQUIRE(lines.size() == 1 + 16 + 1);  // header, Zeek's 16 transactions, counts
  CHECK(lines.front().find("tid unit  fc function") != std::string::npos);
  int port = 55480;
  for (size_t i = 1; i <= 16; ++i, ++port) {
    if (port == 55492) ++port;  // no connection from it in the capture (Zeek lists none)
    const auto f = fields(lines[i]);
    INFO(lines[i]);
    REQUIRE(f.size() >= 11);
    CHECK(f[1] == "118.189.96.132:" + std::to_string(port));
    CHECK(f[2] == "118.189.96.132:502");
    CHECK(f[3] == "1");                          // tid
    CHECK(f[4] == "1");                          // unit
    CHECK(f[5] == (i % 2 == 1 ? "15" : "1"));  // write coils, read coils by turns
    CHECK(f[f.size() - 4] == "0");               // address
    CHECK(f[f.size() - 3] == "3");               // count
    CHECK(f[f.size() - 2] == "ok");
    CHECK(std::stod(f.back()) > 0.0);
    CHECK(std::stod(f.back()) < 1.0);            // ms: server and client on one host
  }
  CHECK(lines.back().find("# 16 transactions: 16 answered (0 exceptions)") == 0);
  CHECK(lines.back().find("0 retransmissions") != std::string::npos);

  const Run e = hild({"modbus", "decode", sics}, tmp.path);
  CHECK(e.rc == 0);
  CHECK(e.out.find("23 Read/Write Multiple Registers") != std::string::npos);
  REQUIRE(lines_of(e.out).size() == 3);
  CHECK(lines_of(e.out)[1].find("exception 10 (gateway path unavailable)") != std::string::npos);
  CHECK(fields(lines_of(e.out)[1]).back() == "2.760");  // ms, as tshark's frame times differ

  const Run bad = hild({"modbus", "decode", tmp.path + "/none.pcap"}, tmp.path);
  CHECK(bad.rc == 2);
  CHECK(lines_of(bad.out).size() == 1);
  CHECK(bad.out.find("none.pcap") != std::string::npos);
}

TEST_CASE("rise-hild dbc decode reads the same car capture as candump, BLF and pcap alike", "[hil][blf][pcap]") {
  const std::string dbc = data_file("can/opendbc/toyota_iQ_2009_can.dbc");
  const std::string log = data_file("can/CANBUSlogs-yaris09/steering.log");
  REQUIRE_DATA(dbc);
  REQUIRE_DATA(log);
  if (std::system("/usr/bin/python3 -c 'import can' >/dev/null 2>&1") != 0) {
    WARN("skipped: /usr/bin/python3 with python3-can (Debian) is not installed");
    return;
  }
  TempDir tmp;
  const std::string blf = tmp.path + "/steering.blf";
  REQUIRE(std::system(("TZ=UTC /usr/bin/python3 " + std::string(RISE_SOURCE_DIR) + "/tests/hil_io/python_can_blf.py write '" +
                       log + "' '" + blf + "'").c_str()) == 0);
  const std::string pcap = tmp.path + "/steering.pcap";
  write_pcap(log, pcap);

  // MANIFEST.md: 1769 frames, 1128 with a message in the DBC.
  const auto decoded = [](const std::string& text) {
    std::vector<std::string> out;
    for (const auto& line : lines_of(text)) {
      const size_t at = line.find(") ");
      if (line.rfind("# ", 0) != 0) out.push_back(line.substr(line.find(' ', at + 2) + 1));  // without time and channel
    }
    return out;
  };
  const Run from_log = hild({"dbc", "decode", dbc, log}, tmp.path);
  REQUIRE(from_log.rc == 0);
  CHECK(from_log.out.find("# 1769 frames: 1128 with a message") != std::string::npos);
  for (const auto& file : {blf, pcap}) {
    INFO(file);
    const Run r = hild({"dbc", "decode", dbc, file}, tmp.path);
    REQUIRE(r.rc == 0);
    CHECK(r.out.find("# 1769 frames: 1128 with a message") != std::string::npos);
    CHECK(decoded(r.out) == decoded(from_log.out));
  }
}

TEST_CASE("rise-hild verify passes the CAN golden session replayed from a BLF and a pcap of its capture", "[hil][blf][pcap]") {
  const std::string dir = std::string(RISE_SOURCE_DIR) + "/tests/data/replay/can";
  if (std::system("/usr/bin/python3 -c 'import can' >/dev/null 2>&1") != 0) {
    WARN("skipped: /usr/bin/python3 with python3-can (Debian) is not installed");
    return;
  }
  TempDir tmp;
  const std::string blf = tmp.path + "/console.blf";
  REQUIRE(std::system(("TZ=UTC /usr/bin/python3 " + std::string(RISE_SOURCE_DIR) + "/tests/hil_io/python_can_blf.py write '" +
                       dir + "/console.log' '" + blf + "'").c_str()) == 0);
  const std::string pcap = tmp.path + "/console.pcap";
  write_pcap(dir + "/console.log", pcap);
  for (const auto& file : {blf, pcap}) {
    INFO(file);
    const Run r = hild({"verify", "--capture", "console=" + file, "--golden", dir + "/panel_state.lcmlog"}, tmp.path);
    CHECK(r.rc == 0);
    CHECK(r.out.find("pass: 212 of 212 PanelState messages") != std::string::npos);
  }
}
