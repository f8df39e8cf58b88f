// Modbus/TCP transactions from real captures (Zeek's test traces), checked
// against Zeek's own decoding of modbusSmall.pcap; segmentation, packing and
// retransmission on the same traffic rewritten by libpcap.
#include <catch2/catch.hpp>

#include <pcap/pcap.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "hil/io/candump_log.hpp"
#include "hil/io/modbus_capture.hpp"
#include "hil/io/replay_modbus_link.hpp"

using namespace rise::hil::io;

namespace {

std::string zeek_file(const std::string& name) {
  const char* root = std::getenv("RISE_TEST_DATA");
  if (root == nullptr) return {};
  const std::string path = std::string(root) + "/modbus/zeek/" + name;
  return std::filesystem::exists(path) ? path : std::string{};
}

#define REQUIRE_DATA(path)                               \
  if ((path).empty()) {                                  \
    WARN("skipped: a file of RISE_TEST_DATA is absent"); \
    return;                                              \
  }

// A request as Zeek's baseline lists it.
struct ZeekRequest {
  int orig_port = 0, tid = 0, unit = 0, function = 0, address = -1, count = -1;
  bool answered = false;
};

// Reads coil_parsing_small/output: modbus_message events (T: from the
// client) give each request and its response; the read-coils and
// write-multiple-coils request events give address and count.
std::vector<ZeekRequest> zeek_requests(const std::string& output) {
  std::ifstream in(output);
  const std::regex message(R"(modbus_message, \[.*orig_p=(\d+)/tcp.*\], \[tid=(\d+), pid=0, uid=(\d+), function_code=(\d+), len=\d+\], ([TF]))");
  const std::regex read(R"(modbus_read_coils_request, \[.*orig_p=(\d+)/tcp.*\], \[tid=(\d+), .*\], (\d+), (\d+)$)");
  const std::regex write(R"(modbus_write_multiple_coils_request, \[.*orig_p=(\d+)/tcp.*\], \[tid=(\d+), .*\], (\d+), \[([TF, ]*)\]$)");
  std::vector<ZeekRequest> requests;
  const auto find = [&](int port, int tid) -> ZeekRequest* {
    for (auto& r : requests)
      if (r.orig_port == port && r.tid == tid) return &r;
    return nullptr;
  };
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  std::smatch m;
  for (const bool from_client : {true, false}) {  // the baseline is sorted: responses may come first
    for (const auto& line : lines) {
      if (!std::regex_search(line, m, message) || (m[5] == "T") != from_client) continue;
      const int port = std::stoi(m[1]), tid = std::stoi(m[2]);
      if (from_client) requests.push_back({port, tid, std::stoi(m[3]), std::stoi(m[4])});
      else if (ZeekRequest* r = find(port, tid)) r->answered = true;
    }
  }
  for (const auto& line : lines) {
    if (std::regex_search(line, m, read)) {
      ZeekRequest* r = find(std::stoi(m[1]), std::stoi(m[2]));
      REQUIRE(r != nullptr);
      r->address = std::stoi(m[3]);
      r->count = std::stoi(m[4]);
    } else if (std::regex_search(line, m, write)) {
      ZeekRequest* r = find(std::stoi(m[1]), std::stoi(m[2]));
      REQUIRE(r != nullptr);
      r->address = std::stoi(m[3]);
      const std::string coils = m[4];
      r->count = static_cast<int>(std::count(coils.begin(), coils.end(), 'T') + std::count(coils.begin(), coils.end(), 'F'));
    }
  }
  return requests;
}

int client_port(const ModbusCaptureTransaction& t) { return std::stoi(t.client.substr(t.client.rfind(':') + 1)); }

struct Packet {
  pcap_pkthdr header;
  std::vector<u_char> bytes;
};

std::vector<Packet> read_packets(const std::string& path) {
  char error[PCAP_ERRBUF_SIZE];
  pcap_t* p = pcap_open_offline(path.c_str(), error);
  REQUIRE(p != nullptr);
  std::vector<Packet> packets;
  pcap_pkthdr* h;
  const u_char* data;
  while (pcap_next_ex(p, &h, &data) == 1) packets.push_back({*h, std::vector<u_char>(data, data + h->caplen)});
  pcap_close(p);
  return packets;
}

void write_packets(const std::string& path, const std::vector<Packet>& packets) {
  pcap_t* dead = pcap_open_dead(DLT_EN10MB, 65535);
  pcap_dumper_t* dump = pcap_dump_open(dead, path.c_str());
  REQUIRE(dump != nullptr);
  for (const auto& p : packets) pcap_dump(reinterpret_cast<u_char*>(dump), &p.header, p.bytes.data());
  pcap_dump_close(dump);
  pcap_close(dead);
}

// Offsets of an Ethernet/IPv4/TCP packet: where the TCP payload starts.
size_t payload_at(const Packet& p) {
  const size_t ip = 14, tcp = ip + static_cast<size_t>(p.bytes[ip] & 0x0F) * 4;
  return tcp + static_cast<size_t>(p.bytes[tcp + 12] >> 4) * 4;
}

void set_lengths(Packet& p) {
  const size_t ip_len = p.bytes.size() - 14;
  p.bytes[16] = static_cast<u_char>(ip_len >> 8);
  p.bytes[17] = static_cast<u_char>(ip_len);
  p.header.caplen = p.header.len = static_cast<bpf_u_int32>(p.bytes.size());
}

// The segment cut in two after `first` payload bytes (the second's sequence
// number moved on by as much).
std::pair<Packet, Packet> split(const Packet& p, size_t first) {
  const size_t at = payload_at(p);
  Packet a = p, b = p;
  a.bytes.resize(at + first);
  b.bytes.erase(b.bytes.begin() + static_cast<std::ptrdiff_t>(at), b.bytes.begin() + static_cast<std::ptrdiff_t>(at + first));
  const size_t seq_at = 14 + static_cast<size_t>(p.bytes[14] & 0x0F) * 4 + 4;
  uint32_t seq = static_cast<uint32_t>(p.bytes[seq_at] << 24 | p.bytes[seq_at + 1] << 16 | p.bytes[seq_at + 2] << 8 | p.bytes[seq_at + 3]);
  seq += static_cast<uint32_t>(first);
  for (int i = 0; i < 4; ++i) b.bytes[seq_at + static_cast<size_t>(i)] = static_cast<u_char>(seq >> (24 - 8 * i));
  set_lengths(a);
  set_lengths(b);
  return {a, b};
}

}  // namespace

TEST_CASE("Modbus/TCP from modbusSmall.pcap: every transaction Zeek decodes, with its function, address and count", "[hil_io][modbus]") {
  const std::string pcap = zeek_file("modbusSmall.pcap");
  const std::string baseline = zeek_file("coil_parsing_small/output");
  REQUIRE_DATA(pcap);
  REQUIRE_DATA(baseline);
  const auto zeek = zeek_requests(baseline);
  REQUIRE(zeek.size() == 16);
  const ModbusCapture ours = read_modbus_capture(pcap);
  CHECK(ours.transactions.size() == zeek.size());
  for (const auto& z : zeek) {
    INFO("Zeek: port " << z.orig_port << " tid " << z.tid << " fc " << z.function);
    const ModbusCaptureTransaction* t = nullptr;
    for (const auto& o : ours.transactions)
      if (client_port(o) == z.orig_port && o.transaction_id == z.tid) t = &o;
    REQUIRE(t != nullptr);
    CHECK(t->unit == z.unit);
    CHECK(t->function == z.function);
    REQUIRE(z.address >= 0);
    CHECK(t->address == std::optional<uint16_t>(static_cast<uint16_t>(z.address)));
    CHECK(t->count == std::optional<uint16_t>(static_cast<uint16_t>(z.count)));
    CHECK(t->response_us.has_value() == z.answered);
    CHECK_FALSE(t->exception.has_value());
    if (t->response_us) CHECK(*t->response_us >= t->request_us);
  }
  CHECK(ours.stats.requests == 16);
  CHECK(ours.stats.responses == 16);
  CHECK(ours.stats.exceptions == 0);
  CHECK(ours.stats.retransmissions == 0);
  CHECK(ours.stats.unmatched_responses == 0);
  CHECK(ours.stats.malformed == 0);
  CHECK(ours.stats.packets == 166);  // MANIFEST.md
}

TEST_CASE("Modbus/TCP exceptions of real PLCs: FC 23 answered 0x97, FC 43 answered 0xAB", "[hil_io][modbus]") {
  const std::string sics = zeek_file("4SICS-GeekLounge-151022-min.pcap");
  const std::string eit = zeek_file("modbus-eit.pcap");
  REQUIRE_DATA(sics);
  REQUIRE_DATA(eit);
  const ModbusCapture a = read_modbus_capture(sics);
  REQUIRE(a.transactions.size() == 1);
  CHECK(a.transactions[0].function == 23);
  CHECK(a.transactions[0].transaction_id == 11);
  CHECK(a.transactions[0].exception == std::optional<uint8_t>(10));  // gateway path unavailable
  CHECK(a.transactions[0].response_pdu.at(0) == 0x97);
  CHECK(std::llabs(*a.transactions[0].response_us - a.transactions[0].request_us - 2760) <= 1);
  CHECK(a.stats.exceptions == 1);
  const ModbusCapture b = read_modbus_capture(eit);
  REQUIRE(b.transactions.size() == 2);
  CHECK(b.transactions[0].function == 43);
  CHECK_FALSE(b.transactions[0].exception.has_value());
  CHECK(b.transactions[1].unit == 255);
  CHECK(b.transactions[1].exception == std::optional<uint8_t>(4));  // server device failure
  CHECK(b.stats.exceptions == 1);
}

TEST_CASE("Modbus/TCP: ADUs split across segments or packed into one, retransmissions counted", "[hil_io][modbus]") {
  const std::string pcap = zeek_file("modbusSmall.pcap");
  REQUIRE_DATA(pcap);
  auto packets = read_packets(pcap);
  std::vector<size_t> modbus;  // packets with a Modbus payload
  for (size_t i = 0; i < packets.size(); ++i) {  // by the IP length: short frames carry Ethernet padding
    const size_t ip_end = 14 + static_cast<size_t>(packets[i].bytes[16] << 8 | packets[i].bytes[17]);
    if (packets[i].bytes[23] == 6 && ip_end > payload_at(packets[i])) modbus.push_back(i);  // TCP, not DNS
  }
  REQUIRE(modbus.size() == 32);
  std::vector<Packet> out;
  for (size_t i = 0; i < packets.size(); ++i) {
    const Packet& p = packets[i];
    if (i == modbus[0]) {  // the first request in three segments, the middle one sent twice
      const auto [a, rest] = split(p, 5);
      const auto [b, c] = split(rest, 4);
      out.insert(out.end(), {a, b, b, c});
    } else if (i == modbus[2]) {  // a second request (tid 2) packed behind the third
      Packet twice = p;
      const size_t at = payload_at(p);
      std::vector<u_char> adu(p.bytes.begin() + static_cast<std::ptrdiff_t>(at), p.bytes.end());
      adu[1] = 2;
      twice.bytes.insert(twice.bytes.end(), adu.begin(), adu.end());
      set_lengths(twice);
      out.push_back(twice);
    } else if (i == modbus[5]) {  // a response sent again whole
      out.insert(out.end(), {p, p});
    } else {
      out.push_back(p);
    }
  }
  const std::string path = std::filesystem::temp_directory_path() / ("rise_modbus_capture_" + std::to_string(::getpid()) + ".pcap");
  write_packets(path, out);
  const ModbusCapture ours = read_modbus_capture(path);
  std::filesystem::remove(path);
  const ModbusCapture whole = read_modbus_capture(pcap);
  REQUIRE(ours.transactions.size() == whole.transactions.size() + 1);
  CHECK(ours.stats.retransmissions == 2);
  CHECK(ours.stats.malformed == 0);
  CHECK(ours.stats.unmatched_responses == 0);
  size_t j = 0;
  for (const auto& t : ours.transactions) {
    if (t.transaction_id == 2) {
      CHECK_FALSE(t.response_us.has_value());  // its server never saw it
      CHECK(t.request_pdu == ours.transactions[1].request_pdu);
      continue;
    }
    INFO("transaction " << j);
    CHECK(t.request_pdu == whole.transactions[j].request_pdu);
    CHECK(t.response_pdu == whole.transactions[j].response_pdu);
    CHECK(t.response_us == whole.transactions[j].response_us);
    ++j;
  }
  CHECK(j == whole.transactions.size());
}

TEST_CASE("Modbus/TCP capture: a CAN capture or a missing file is refused with its name", "[hil_io][modbus]") {
  CHECK_THROWS_WITH(read_modbus_capture("/nonexistent/x.pcap"), Catch::Contains("/nonexistent/x.pcap"));
  pcap_t* dead = pcap_open_dead(227, 65535);
  const std::string can = std::filesystem::temp_directory_path() / ("rise_modbus_can_" + std::to_string(::getpid()) + ".pcap");
  pcap_dump_close(pcap_dump_open(dead, can.c_str()));
  pcap_close(dead);
  CHECK_THROWS_WITH(read_modbus_capture(can), Catch::Contains("link type 227"));
  std::filesystem::remove(can);
}

TEST_CASE("replay://modbusSmall.pcap on a Modbus source answers each coil read as the capture's server did", "[hil_io][modbus]") {
  const std::string pcap = zeek_file("modbusSmall.pcap");
  const std::string baseline = zeek_file("coil_parsing_small/output");
  REQUIRE_DATA(pcap);
  REQUIRE_DATA(baseline);
  // Zeek's read-coils responses by client port (the order they came in).
  std::map<int, std::vector<uint8_t>> zeek;
  std::ifstream in(baseline);
  const std::regex response(R"(modbus_read_coils_response, \[.*orig_p=(\d+)/tcp.*\], \[([TF, ]*)\]$)");
  std::smatch m;
  for (std::string line; std::getline(in, line);) {
    if (!std::regex_search(line, m, response)) continue;
    const std::string bits = m[2];
    std::vector<uint8_t> v;
    for (const char c : bits)
      if (c == 'T' || c == 'F') v.push_back(c == 'T');
    zeek[std::stoi(m[1])] = v;
  }
  REQUIRE(zeek.size() == 8);
  CHECK(looks_like_modbus_capture(pcap));
  const auto link = open_modbus_replay("replay://" + pcap + "?fast=1");
  REQUIRE(link->is_open());
  for (const auto& [port, bits] : zeek) {
    INFO("the answer to port " << port);
    std::array<uint8_t, 3> coils{};
    REQUIRE(link->read_coils(0, coils).ok());
    CHECK(std::vector<uint8_t>(coils.begin(), coils.end()) == std::vector<uint8_t>(bits.begin(), bits.begin() + 3));
    const std::array<uint8_t, 3> write{1, 0, 1};
    CHECK(link->write_coils(0, write).ok());  // accepted and dropped, as the trace replay does
  }
  // Not in the capture: exception 02, as a server without it.
  std::array<uint16_t, 1> reg{};
  CHECK(link->read_holding_registers(0, reg).exception_code == 2);
}

namespace {

// One Ethernet/IPv4/TCP segment from 10.0.0.1:40000 to 10.0.0.2:502 carrying
// `adu` at sequence number `seq`.
Packet modbus_segment(const std::vector<u_char>& adu, u_char seq) {
  Packet p{};
  p.header.ts.tv_sec = 1400547199;
  p.bytes = {0, 1, 2, 3, 4, 5, 0, 1, 2, 3, 4, 6, 0x08, 0x00,                                  // Ethernet
             0x45, 0, 0, 0, 0, 1, 0x40, 0, 64, 6, 0, 0, 10, 0, 0, 1, 10, 0, 0, 2,             // IPv4
             0x9C, 0x40, 0x01, 0xF6, 0, 0, 0, seq, 0, 0, 0, 0, 0x50, 0x18, 0x10, 0, 0, 0, 0, 0};  // TCP
  for (const u_char b : adu) p.bytes.push_back(b);  // (g++ 12 warns a false -Warray-bounds on insert here)
  set_lengths(p);
  return p;
}

}  // namespace

// Found by the logs fuzz target (tests/fuzz/logs_fuzz.cpp, a Modbus capture):
// an unanswered (or refused) Write Multiple Coils became a trace line without
// the coils it wrote, which the trace reader refuses ("expected one string of
// count=3 bits"); a write's line always says what it wrote.
TEST_CASE("Modbus/TCP capture: an unanswered write's trace line says what it wrote; a short one has none", "[hil_io][modbus]") {
  const std::string path =
      std::filesystem::temp_directory_path() / ("rise_modbus_write_" + std::to_string(::getpid()) + ".pcap");
  // FC 15 at 0, 3 coils, 1 byte: 1 0 1; then FC 15 at 8, 9 coils, but 1 byte of them.
  write_packets(path, {modbus_segment({0, 1, 0, 0, 0, 8, 1, 15, 0, 0, 0, 3, 1, 0x05}, 1),
                       modbus_segment({0, 2, 0, 0, 0, 8, 1, 15, 0, 8, 0, 9, 1, 0xFF}, 15)});
  const ModbusCapture capture = read_modbus_capture(path);
  std::filesystem::remove(path);
  REQUIRE(capture.transactions.size() == 2);
  const auto records = modbus_trace_from_capture(capture, "plc");
  REQUIRE(records.size() == 1);
  CHECK(records[0].result.status == ModbusStatus::Timeout);
  CHECK(records[0].values == std::vector<uint16_t>{1, 0, 1});
  const std::string line = format_modbus_trace_line(records[0]);
  const ModbusTraceParse back = parse_modbus_trace_line(line);
  INFO(line);
  REQUIRE(back.ok);
  CHECK(format_modbus_trace_line(back.record) == line);
}

// Found by the logs fuzz target: a classic pcap stores a packet's seconds as a
// signed 32-bit number and its microseconds unchecked, so a request came out
// at (-1384470635.-886822), a time no trace line can carry. Such a packet is
// counted malformed; the next one is read.
TEST_CASE("Modbus/TCP capture: a packet time before 1970 or with microseconds past a second is malformed", "[hil_io][modbus]") {
  const std::string path =
      std::filesystem::temp_directory_path() / ("rise_modbus_time_" + std::to_string(::getpid()) + ".pcap");
  Packet before = modbus_segment({0, 1, 0, 0, 0, 6, 1, 1, 0, 0, 0, 3}, 1);
  before.header.ts.tv_sec = -1384470635;
  Packet micros = modbus_segment({0, 2, 0, 0, 0, 6, 1, 1, 0, 0, 0, 3}, 13);
  micros.header.ts.tv_usec = 2'000'000;
  const Packet good = modbus_segment({0, 3, 0, 0, 0, 6, 1, 1, 0, 0, 0, 3}, 25);
  write_packets(path, {before, micros, good});
  const ModbusCapture capture = read_modbus_capture(path);
  std::filesystem::remove(path);
  CHECK(capture.stats.malformed == 2);
  REQUIRE(capture.transactions.size() == 1);
  CHECK(capture.transactions[0].transaction_id == 3);
  CHECK(capture.transactions[0].request_us == 1400547199'000'000);
  CHECK(capture_time_us(-1, 0) == std::nullopt);
  CHECK(capture_time_us(999'999'999'999, 999'999) == 999'999'999'999'999'999);
  CHECK(capture_time_us(1'000'000'000'000, 0) == std::nullopt);
}

// Found by the logs fuzz target: a capture whose clock steps back between a
// request and its answer gave a trace line with rtt_us=-145, which the trace
// reader refuses. A trace's rtt is never negative.
TEST_CASE("Modbus/TCP capture: an answer stamped before its request has rtt 0 in the trace", "[hil_io][modbus]") {
  ModbusCapture capture;
  ModbusCaptureTransaction t;
  t.request_us = 1400547213'667867, t.response_us = 1400547213'667722;
  t.client = "10.0.0.1:40000", t.server = "10.0.0.2:502", t.unit = 1, t.function = 1, t.address = 0, t.count = 3;
  t.request_pdu = {1, 0, 0, 0, 3}, t.response_pdu = {1, 1, 0x04};
  capture.transactions = {t};
  const auto records = modbus_trace_from_capture(capture, "fuzz");
  REQUIRE(records.size() == 1);
  CHECK(records[0].rtt_us == 0);
  CHECK(records[0].values == std::vector<uint16_t>{0, 0, 1});
  const std::string line = format_modbus_trace_line(records[0]);
  INFO(line);
  CHECK(parse_modbus_trace_line(line).ok);
}
