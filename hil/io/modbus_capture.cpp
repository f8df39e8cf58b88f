#include "hil/io/modbus_capture.hpp"
#include "hil/io/candump_log.hpp"

#include <arpa/inet.h>
#include <pcap/pcap.h>

#include <algorithm>
#include <map>
#include <memory>
#include <stdexcept>
#include <tuple>

namespace rise::hil::io {

namespace {

uint16_t be16(const uint8_t* p) { return static_cast<uint16_t>(p[0] << 8 | p[1]); }
uint32_t be32(const uint8_t* p) { return static_cast<uint32_t>(be16(p)) << 16 | be16(p + 2); }

constexpr size_t kMbapSize = 7;         // transaction, protocol, length, unit
constexpr uint16_t kMaxMbapLength = 254;  // unit + the largest PDU (253)
constexpr int kDltRaw = 12, kDltRawAlt = 101, kDltEthernet = 1, kDltSll = 113, kDltSll2 = 276;

// One TCP segment's view of the packet.
struct Segment {
  std::string src, dst;  // "ADDRESS:PORT"
  uint16_t src_port = 0, dst_port = 0;
  uint32_t seq = 0;
  bool syn = false;
  const uint8_t* payload = nullptr;
  size_t size = 0;
};

std::string address_text(int family, const uint8_t* bytes, uint16_t port) {
  char text[INET6_ADDRSTRLEN] = "";
  ::inet_ntop(family, bytes, text, sizeof text);
  return (family == AF_INET6 ? "[" + std::string(text) + "]" : std::string(text)) + ":" + std::to_string(port);
}

bool parse_tcp(const uint8_t* p, size_t n, int family, const uint8_t* src_ip, const uint8_t* dst_ip, Segment& s) {
  if (n < 20) return false;
  const size_t header = static_cast<size_t>(p[12] >> 4) * 4;
  if (header < 20 || header > n) return false;
  s.src_port = be16(p);
  s.dst_port = be16(p + 2);
  s.seq = be32(p + 4);
  s.syn = (p[13] & 0x02) != 0;
  s.src = address_text(family, src_ip, s.src_port);
  s.dst = address_text(family, dst_ip, s.dst_port);
  s.payload = p + header;
  s.size = n - header;
  return true;
}

// IPv4 or IPv6 (without extension headers) carrying TCP.
bool parse_ip(const uint8_t* p, size_t n, Segment& s) {
  if (n >= 20 && p[0] >> 4 == 4) {
    const size_t header = static_cast<size_t>(p[0] & 0x0F) * 4;
    const size_t total = be16(p + 2);
    const bool fragment = (be16(p + 6) & 0x3FFF) != 0;
    if (p[9] != 6 || header < 20 || total < header || fragment) return false;
    return parse_tcp(p + header, std::min(n, total) - header, AF_INET, p + 12, p + 16, s);
  }
  if (n >= 40 && p[0] >> 4 == 6) {
    if (p[6] != 6) return false;
    return parse_tcp(p + 40, std::min<size_t>(n - 40, be16(p + 4)), AF_INET6, p + 8, p + 24, s);
  }
  return false;
}

// The IP packet inside a link-layer frame.
bool parse_link(int link, const uint8_t* p, size_t n, Segment& s) {
  uint16_t type = 0;
  if (link == kDltEthernet) {
    if (n < 14) return false;
    type = be16(p + 12);
    p += 14;
    n -= 14;
    while ((type == 0x8100 || type == 0x88A8) && n >= 4) {  // VLAN tags
      type = be16(p + 2);
      p += 4;
      n -= 4;
    }
  } else if (link == kDltSll) {
    if (n < 16) return false;
    type = be16(p + 14);
    p += 16;
    n -= 16;
  } else if (link == kDltSll2) {
    if (n < 20) return false;
    type = be16(p);
    p += 20;
    n -= 20;
  } else {
    type = n > 0 && p[0] >> 4 == 6 ? 0x86DD : 0x0800;
  }
  if (type != 0x0800 && type != 0x86DD) return false;
  return parse_ip(p, n, s);
}

// One direction of a TCP connection as a byte stream.
struct Stream {
  bool started = false;
  uint32_t next_seq = 0;
  std::vector<uint8_t> bytes;
};

class Decoder {
 public:
  explicit Decoder(uint16_t port) : port_(port) {}

  void segment(const Segment& s, int64_t time_us) {
    const bool request = s.dst_port == port_;
    if (!request && s.src_port != port_) return;
    Stream& stream = streams_[{s.src, s.dst}];
    if (s.syn) {  // the stream starts after the SYN's sequence number
      stream = Stream{true, s.seq + 1, {}};
      return;
    }
    if (s.size == 0) return;
    ++out_.stats.modbus_segments;
    const uint8_t* data = s.payload;
    size_t size = s.size;
    if (!stream.started) stream = Stream{true, s.seq, {}};
    const auto behind = static_cast<int32_t>(stream.next_seq - s.seq);
    if (behind < 0) {  // bytes were lost: what was buffered cannot be finished
      ++out_.stats.malformed;
      stream.bytes.clear();
    } else if (behind > 0) {  // bytes seen already: a retransmission
      ++out_.stats.retransmissions;
      if (static_cast<size_t>(behind) >= size) return;
      data += behind;
      size -= static_cast<size_t>(behind);
    }
    stream.bytes.insert(stream.bytes.end(), data, data + size);
    stream.next_seq = s.seq + static_cast<uint32_t>(s.size);
    adus(stream, s, request, time_us);
  }

  ModbusCapture& result() { return out_; }

 private:
  using Key = std::tuple<std::string, std::string, uint16_t, uint8_t>;  // client, server, tid, unit

  void adus(Stream& stream, const Segment& s, bool request, int64_t time_us) {
    size_t at = 0;
    while (stream.bytes.size() - at >= kMbapSize) {
      const uint8_t* adu = stream.bytes.data() + at;
      const uint16_t length = be16(adu + 4);
      if (be16(adu + 2) != 0 || length < 2 || length > kMaxMbapLength) {
        ++out_.stats.malformed;  // not MBAP: nothing after it can be framed
        at = stream.bytes.size();
        break;
      }
      if (stream.bytes.size() - at < 6u + length) break;  // the rest comes in a later segment
      const std::vector<uint8_t> pdu(adu + kMbapSize, adu + 6 + length);
      if (request) on_request(s, be16(adu), adu[6], pdu, time_us);
      else on_response(s, be16(adu), adu[6], pdu, time_us);
      at += 6u + length;
    }
    stream.bytes.erase(stream.bytes.begin(), stream.bytes.begin() + static_cast<std::ptrdiff_t>(at));
  }

  void on_request(const Segment& s, uint16_t tid, uint8_t unit, const std::vector<uint8_t>& pdu, int64_t time_us) {
    ++out_.stats.requests;
    ModbusCaptureTransaction t;
    t.request_us = time_us;
    t.client = s.src;
    t.server = s.dst;
    t.transaction_id = tid;
    t.unit = unit;
    t.function = pdu[0];
    t.request_pdu = pdu;
    const bool ranged = (t.function >= 1 && t.function <= 4) || t.function == 15 || t.function == 16 || t.function == 23;
    if (pdu.size() >= 5 && ranged) {
      t.address = be16(pdu.data() + 1);
      t.count = be16(pdu.data() + 3);
    } else if (pdu.size() >= 3 && (t.function == 5 || t.function == 6)) {
      t.address = be16(pdu.data() + 1);
      t.count = 1;
    }
    pending_[{t.client, t.server, tid, unit}] = out_.transactions.size();
    out_.transactions.push_back(std::move(t));
  }

  void on_response(const Segment& s, uint16_t tid, uint8_t unit, const std::vector<uint8_t>& pdu, int64_t time_us) {
    ++out_.stats.responses;
    const auto it = pending_.find({s.dst, s.src, tid, unit});
    if (it == pending_.end()) {
      ++out_.stats.unmatched_responses;
      return;
    }
    ModbusCaptureTransaction& t = out_.transactions[it->second];
    pending_.erase(it);
    t.response_us = time_us;
    t.response_pdu = pdu;
    if ((pdu[0] & 0x80) != 0) {
      ++out_.stats.exceptions;
      t.exception = pdu.size() >= 2 ? pdu[1] : 0;
    }
  }

  uint16_t port_;
  ModbusCapture out_;
  std::map<std::pair<std::string, std::string>, Stream> streams_;
  std::map<Key, size_t> pending_;
};

}  // namespace

ModbusCapture read_modbus_capture(const std::string& path, uint16_t port) {
  char error[PCAP_ERRBUF_SIZE] = "";
  std::unique_ptr<pcap_t, void (*)(pcap_t*)> pcap(
      pcap_open_offline_with_tstamp_precision(path.c_str(), PCAP_TSTAMP_PRECISION_MICRO, error), pcap_close);
  if (!pcap) throw std::runtime_error(path + ": pcap: " + error);
  const int link = pcap_datalink(pcap.get());
  if (link != kDltEthernet && link != kDltSll && link != kDltSll2 && link != kDltRaw && link != kDltRawAlt) {
    const char* name = pcap_datalink_val_to_name(link);
    throw std::runtime_error(path + ": pcap: link type " + std::to_string(link) + " (" + (name ? name : "?") +
                             ") carries no IP (Ethernet, Linux cooked or raw IP)");
  }
  Decoder decoder(port);
  pcap_pkthdr* header = nullptr;
  const u_char* packet = nullptr;
  int rc = 0;
  while ((rc = pcap_next_ex(pcap.get(), &header, &packet)) == 1) {
    ++decoder.result().stats.packets;
    Segment s;
    if (!parse_link(link, packet, header->caplen, s)) continue;
    const auto time_us = capture_time_us(header->ts.tv_sec, header->ts.tv_usec);
    if (!time_us) {
      ++decoder.result().stats.malformed;  // a time no trace line can carry (found by the logs fuzz target)
      continue;
    }
    decoder.segment(s, *time_us);
  }
  if (rc != PCAP_ERROR_BREAK) ++decoder.result().stats.malformed;  // a cut last record
  return std::move(decoder.result());
}

bool looks_like_modbus_capture(const std::string& path) {
  char error[PCAP_ERRBUF_SIZE] = "";
  std::unique_ptr<pcap_t, void (*)(pcap_t*)> pcap(pcap_open_offline(path.c_str(), error), pcap_close);
  if (!pcap) return false;
  const int link = pcap_datalink(pcap.get());
  if (link == kDltEthernet || link == kDltRaw || link == kDltRawAlt) return true;
  if (link != kDltSll && link != kDltSll2) return false;
  pcap_pkthdr* header = nullptr;
  const u_char* packet = nullptr;
  if (pcap_next_ex(pcap.get(), &header, &packet) != 1) return true;
  const size_t at = link == kDltSll ? 14 : 0;
  if (header->caplen < at + 2) return true;
  const uint16_t protocol = be16(packet + at);
  return protocol != 0x000C && protocol != 0x000D;  // CAN, CAN FD
}

namespace {

// Bits of a coil/discrete-input PDU, first address in the lowest bit.
void unpack_bits(const uint8_t* bytes, size_t size, uint16_t count, std::vector<uint16_t>& out) {
  for (uint16_t i = 0; i < count && i / 8u < size; ++i) out.push_back((bytes[i / 8] >> (i % 8)) & 1u);
}

void unpack_registers(const uint8_t* bytes, size_t size, std::vector<uint16_t>& out) {
  for (size_t i = 0; i + 1 < size; i += 2) out.push_back(be16(bytes + i));
}

// The values a trace line carries: the read's answer, or what was written.
// False when the PDU holds fewer than count of them.
bool trace_values(const ModbusCaptureTransaction& t, ModbusTraceRecord& r) {
  const bool bits = is_bit_function(r.function);
  const bool write = t.function == 15 || t.function == 16;
  const std::vector<uint8_t>& pdu = write ? t.request_pdu : t.response_pdu;
  const size_t at = write ? 6 : 2;  // after the byte count
  if (pdu.size() < at) return false;
  const size_t size = std::min<size_t>(pdu[at - 1], pdu.size() - at);
  if (bits) unpack_bits(pdu.data() + at, size, r.count, r.values);
  else unpack_registers(pdu.data() + at, size, r.values);
  return r.values.size() >= r.count;
}

}  // namespace

std::vector<ModbusTraceRecord> modbus_trace_from_capture(const ModbusCapture& capture, const std::string& source) {
  constexpr int64_t kNoAnswerUs = 1'000'000;
  std::vector<ModbusTraceRecord> records;
  const auto& all = capture.transactions;
  for (size_t i = 0; i < all.size(); ++i) {
    const ModbusCaptureTransaction& t = all[i];
    const bool known = (t.function >= 1 && t.function <= 4) || t.function == 15 || t.function == 16;
    if (!known || !t.address || !t.count) continue;
    ModbusTraceRecord r;
    r.time_us = t.request_us;
    r.source = source;
    r.unit = t.unit;
    r.function = static_cast<ModbusFunction>(t.function);
    r.address = *t.address;
    r.count = *t.count;
    // A write's line always says what it wrote, answered or not: one whose
    // request holds fewer values than its count has no line.
    const bool write = t.function == 15 || t.function == 16;
    if (write && !trace_values(t, r)) continue;
    if (!t.response_us) {
      r.result.status = ModbusStatus::Timeout;
      r.rtt_us = kNoAnswerUs;
      for (size_t j = i + 1; j < all.size(); ++j) {
        if (all[j].client != t.client || all[j].server != t.server) continue;
        r.rtt_us = all[j].request_us - t.request_us;  // (clamped below)
        break;
      }
    } else if (t.exception) {
      r.rtt_us = *t.response_us - t.request_us;
      r.result = {ModbusStatus::Exception, *t.exception};
    } else {
      r.rtt_us = *t.response_us - t.request_us;
      if (!write && !trace_values(t, r)) r.result.status = ModbusStatus::Error;  // an answer too short for its count
    }
    // A capture's clock may step back between request and answer (found by
    // the logs fuzz target): a trace's rtt is never negative.
    r.rtt_us = std::max<int64_t>(r.rtt_us, 0);
    if (write || r.result.ok()) r.values.resize(r.count);
    else r.values.clear();
    records.push_back(std::move(r));
  }
  return records;
}

std::string modbus_function_name(uint8_t function) {
  switch (function) {
    case 1: return "Read Coils";
    case 2: return "Read Discrete Inputs";
    case 3: return "Read Holding Registers";
    case 4: return "Read Input Registers";
    case 5: return "Write Single Coil";
    case 6: return "Write Single Register";
    case 7: return "Read Exception Status";
    case 8: return "Diagnostics";
    case 15: return "Write Multiple Coils";
    case 16: return "Write Multiple Registers";
    case 17: return "Report Server ID";
    case 22: return "Mask Write Register";
    case 23: return "Read/Write Multiple Registers";
    case 43: return "Encapsulated Interface";
    default: return "function " + std::to_string(function);
  }
}

std::string modbus_exception_name(uint8_t code) {
  switch (code) {
    case 1: return "illegal function";
    case 2: return "illegal data address";
    case 3: return "illegal data value";
    case 4: return "server device failure";
    case 5: return "acknowledge";
    case 6: return "server device busy";
    case 8: return "memory parity error";
    case 10: return "gateway path unavailable";
    case 11: return "gateway target failed to respond";
    default: return "exception " + std::to_string(code);
  }
}

}  // namespace rise::hil::io
