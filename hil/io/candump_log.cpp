#include "hil/io/candump_log.hpp"

#include <array>
#include <bit>
#include <cstdio>
#include <cstring>

namespace rise::hil::io {
namespace {

constexpr uint32_t kErrFlag = 0x20000000u;  // CAN_ERR_FLAG in <linux/can.h>
constexpr uint32_t kEffMask = 0x1FFFFFFFu;

int hex_value(char c);

bool parse_hex(std::string_view text, uint32_t& out) {
  if (text.empty() || text.size() > 8) return false;
  out = 0;
  for (char c : text) {
    const int v = hex_value(c);
    if (v < 0) return false;
    out = out << 4 | static_cast<uint32_t>(v);
  }
  return true;
}

// Data bytes as pairs of hex digits; can-utils also allows '.' separators.
bool parse_data(std::string_view text, CanFrame& f, std::size_t max_len) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < text.size();) {
    if (text[i] == '.') {
      ++i;
      continue;
    }
    if (i + 1 >= text.size() || n >= max_len) return false;
    const int hi = hex_value(text[i]), lo = hex_value(text[i + 1]);
    if (hi < 0 || lo < 0) return false;
    f.data[n++] = static_cast<uint8_t>(hi << 4 | lo);
    i += 2;
  }
  f.len = static_cast<uint8_t>(n);
  return true;
}

// Hex digit values, -1 for anything else.
constexpr std::array<int8_t, 256> kHex = [] {
  std::array<int8_t, 256> t{};
  t.fill(-1);
  for (int c = '0'; c <= '9'; ++c) t[static_cast<std::size_t>(c)] = static_cast<int8_t>(c - '0');
  for (int c = 'a'; c <= 'f'; ++c) t[static_cast<std::size_t>(c)] = static_cast<int8_t>(c - 'a' + 10);
  for (int c = 'A'; c <= 'F'; ++c) t[static_cast<std::size_t>(c)] = static_cast<int8_t>(c - 'A' + 10);
  return t;
}();

inline int hex_at(const char* p) { return kHex[static_cast<unsigned char>(*p)]; }

// The value of eight ASCII decimal digits (already checked), with three
// multiplies instead of eight (D. Lemire, "Quickly parsing eight digits",
// 2018: SWAR on a little-endian load).
int64_t eight_digits(const char* p) {
  if constexpr (std::endian::native == std::endian::little) {
    uint64_t v;
    std::memcpy(&v, p, 8);
    v -= 0x3030303030303030ULL;
    v = v * 10 + (v >> 8);
    v = (((v & 0x000000FF000000FFULL) * (100 + (1000000ULL << 32))) +
         (((v >> 16) & 0x000000FF000000FFULL) * (1 + (10000ULL << 32)))) >>
        32;
    return static_cast<int64_t>(v & 0xFFFFFFFFULL);
  } else {
    int64_t v = 0;
    for (int i = 0; i < 8; ++i) v = v * 10 + (p[i] - '0');
    return v;
  }
}
int hex_value(char c) { return kHex[static_cast<unsigned char>(c)]; }

}  // namespace

const char* parse_candump_fast(const char* p, const char* end, CanFrame& f, std::string_view& interface,
                               bool& tx) {
  // Every read checks `end`; any surprise hands the line to the general parser.
  if (p == end || *p != '(') return nullptr;
  ++p;
  // Digit runs are valued in independent pieces, not one long
  // multiply-add chain: that chain was most of the time per line.
  const char* digits = p;
  while (p != end && *p >= '0' && *p <= '9') ++p;
  const auto n = p - digits;
  if (n == 0 || n > 12 || p == end || *p != '.') return nullptr;
  int64_t sec = 0;
  const char* tail = n >= 8 ? p - 8 : p;  // the last eight digits, if there are eight
  for (const char* d = digits; d != tail; ++d) sec = sec * 10 + (*d - '0');
  if (n >= 8) sec = sec * 100'000'000 + eight_digits(tail);
  ++p;
  if (end - p < 8) return nullptr;
  for (int i = 0; i < 6; ++i)
    if (p[i] < '0' || p[i] > '9') return nullptr;
  const int64_t usec = (p[0] * 100 + p[1] * 10 + p[2] - '0' * 111) * 1000 + (p[3] * 100 + p[4] * 10 + p[5] - '0' * 111);
  p += 6;
  if (*p++ != ')' || *p++ != ' ') return nullptr;
  const char* name = p;
  while (p != end && *p != ' ' && *p != '\n' && *p != '\r') ++p;
  if (p == name || p == end || *p != ' ') return nullptr;
  const std::string_view iface(name, static_cast<std::size_t>(p - name));
  ++p;
  uint32_t id = 0;
  const char* id_begin = p;
  for (int v; p != end && (v = hex_at(p)) >= 0; ++p) id = id << 4 | static_cast<uint32_t>(v);
  const auto id_digits = p - id_begin;
  if (p == end || *p != '#' || (id_digits != 3 && id_digits != 8)) return nullptr;
  if (id_digits == 3 && id > 0x7FF) return nullptr;
  ++p;
  uint8_t data[8] = {};
  uint8_t len = 0;
  for (int hi, lo; end - p >= 2 && (hi = hex_at(p)) >= 0 && (lo = hex_at(p + 1)) >= 0; p += 2) {
    if (len == 8) return nullptr;
    data[len++] = static_cast<uint8_t>(hi << 4 | lo);
  }
  bool sent = false;
  if (end - p >= 3 && p[0] == ' ' && (p[1] == 'R' || p[1] == 'T') && (p[2] == '\n' || p[2] == '\r')) {
    sent = p[1] == 'T';
    p += 2;
  }
  if (p != end && *p == '\r') ++p;
  if (p == end || *p != '\n') return nullptr;
  // Field by field, not `f = CanFrame{}`: clearing all 64 data bytes
  // (rep stos) cost more than the rest of the line.
  if (f.len > 8) std::memset(f.data.data() + 8, 0, f.data.size() - 8);
  f.timestamp_us = sec * 1'000'000 + usec;
  f.error = id_digits == 8 && (id & kErrFlag) != 0;
  f.extended = id_digits == 8 && !f.error;
  f.remote = f.fd = f.brs = f.esi = false;
  f.id = id_digits == 8 ? id & kEffMask : id;
  f.len = len;
  std::memcpy(f.data.data(), data, 8);
  interface = iface;
  tx = sent;
  return p + 1;
}

const char* to_string(CandumpError error) {
  switch (error) {
    case CandumpError::None: return "ok";
    case CandumpError::Empty: return "empty line";
    case CandumpError::NoTimestamp: return "no (seconds.micros) timestamp";
    case CandumpError::NoInterface: return "no interface name";
    case CandumpError::BadId: return "bad identifier";
    case CandumpError::BadData: return "bad data bytes";
    case CandumpError::TooLong: return "more data than the frame type holds";
  }
  return "?";
}

std::optional<int64_t> parse_log_time(std::string_view line, std::string_view* rest) {
  if (line.empty() || line.front() != '(') return std::nullopt;
  const auto close = line.find(')');
  const auto dot = line.find('.');
  if (close == std::string_view::npos || dot == std::string_view::npos || dot > close) return std::nullopt;
  int64_t sec = 0, usec = 0;
  // 12 digits of seconds reach year 33658: more is not a time (and would overflow).
  if (dot - 1 == 0 || dot - 1 > 12) return std::nullopt;
  for (char c : line.substr(1, dot - 1)) {
    if (c < '0' || c > '9') return std::nullopt;
    sec = sec * 10 + (c - '0');
  }
  const auto frac = line.substr(dot + 1, close - dot - 1);
  if (frac.empty() || frac.size() > 9) return std::nullopt;
  int digits = 0;
  for (char c : frac) {
    if (c < '0' || c > '9') return std::nullopt;
    if (digits++ < 6) usec = usec * 10 + (c - '0');
  }
  for (; digits < 6; ++digits) usec *= 10;
  if (rest) *rest = line.substr(close + 1);
  return sec * 1'000'000 + usec;
}

void append_log_time(std::string& out, int64_t time_us) {
  char text[48];
  const int n = std::snprintf(text, sizeof text, "(%lld.%06lld)", static_cast<long long>(time_us / 1'000'000),
                              static_cast<long long>(time_us % 1'000'000));
  out.append(text, static_cast<std::size_t>(n));
}

std::optional<int64_t> capture_time_us(int64_t seconds, int64_t micros) {
  if (seconds < 0 || seconds >= 1'000'000'000'000 || micros < 0 || micros >= 1'000'000) return std::nullopt;
  return seconds * 1'000'000 + micros;
}

CandumpParse parse_candump_line(std::string_view line) {
  CandumpParse r;
  std::string_view interface;
  r.error = parse_candump_line(line, r.record.frame, interface, &r.record.tx);
  r.record.interface = std::string(interface);
  return r;
}

CandumpError parse_candump_line(std::string_view line, CanFrame& frame, std::string_view& interface, bool* tx) {
  frame = CanFrame{};
  interface = {};
  if (tx) *tx = false;
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r' || line.back() == ' ')) line.remove_suffix(1);
  while (!line.empty() && line.front() == ' ') line.remove_prefix(1);
  if (line.empty()) return CandumpError::Empty;
  std::string_view rest;
  const std::optional<int64_t> time_us = parse_log_time(line, &rest);
  if (!time_us) return CandumpError::NoTimestamp;
  frame.timestamp_us = *time_us;

  while (!rest.empty() && rest.front() == ' ') rest.remove_prefix(1);
  const auto space = rest.find(' ');
  if (space == std::string_view::npos || space == 0) return CandumpError::NoInterface;
  interface = rest.substr(0, space);
  rest = rest.substr(space + 1);
  while (!rest.empty() && rest.front() == ' ') rest.remove_prefix(1);
  // After the frame candump -x and python-can write the direction (" R" /
  // " T"); anything else there is ignored.
  if (const auto end = rest.find(' '); end != std::string_view::npos) {
    std::string_view after = rest.substr(end);
    while (!after.empty() && after.front() == ' ') after.remove_prefix(1);
    if (tx) *tx = after == "T" || after == "t";
    rest = rest.substr(0, end);
  }

  const auto hash = rest.find('#');
  if (hash == std::string_view::npos) return CandumpError::BadId;
  CanFrame& f = frame;
  uint32_t id = 0;
  if (!parse_hex(rest.substr(0, hash), id)) return CandumpError::BadId;
  if (hash == 3) {
    if (id > 0x7FF) return CandumpError::BadId;
  } else if (hash == 8) {
    f.error = (id & kErrFlag) != 0;  // then the id holds the error class
    f.extended = !f.error;
    id &= kEffMask;
  } else {
    return CandumpError::BadId;
  }
  f.id = id;

  std::string_view data = rest.substr(hash + 1);
  if (!data.empty() && data.front() == '#') {  // CAN FD: flags nibble first
    data.remove_prefix(1);
    if (data.empty()) return CandumpError::BadData;
    const int flags = hex_value(data.front());
    if (flags < 0) return CandumpError::BadData;
    f.fd = true;
    f.brs = flags & 0x1;  // CANFD_BRS
    f.esi = flags & 0x2;  // CANFD_ESI
    data.remove_prefix(1);
    if (!parse_data(data, f, 64)) return CandumpError::TooLong;
    if (!is_fd_length(f.len)) return CandumpError::BadData;
    return CandumpError::None;
  }
  if (!data.empty() && (data.front() == 'R' || data.front() == 'r')) {
    f.remote = true;
    f.len = 0;
    if (data.size() == 2) {
      const int len = hex_value(data[1]);
      if (len < 0 || len > 8) return CandumpError::BadData;
      f.len = static_cast<uint8_t>(len);
    } else if (data.size() > 2) {
      return CandumpError::BadData;
    }
    return CandumpError::None;
  }
  if (!parse_data(data, f, 8)) return data.size() > 16 ? CandumpError::TooLong : CandumpError::BadData;
  return CandumpError::None;
}

std::string format_candump_line(const CanFrame& f, std::string_view interface, CandumpDirection direction) {
  std::string out;
  append_candump_line(out, f, interface, direction);
  return out;
}

void append_candump_line(std::string& out, const CanFrame& f, std::string_view interface,
                         CandumpDirection direction) {
  append_log_time(out, f.timestamp_us);
  out += ' ';
  out += interface;
  char id[16];
  const int id_len = f.error      ? std::snprintf(id, sizeof id, " %08X#", f.id | kErrFlag)
                     : f.extended ? std::snprintf(id, sizeof id, " %08X#", f.id)
                                  : std::snprintf(id, sizeof id, " %03X#", f.id);
  out.append(id, static_cast<std::size_t>(id_len));
  static const char* digits = "0123456789ABCDEF";
  if (f.remote) {
    out += 'R';
    if (f.len) out += digits[f.len & 0xF];
  } else {
    if (f.fd) {
      out += '#';
      out += digits[(f.brs ? 1 : 0) | (f.esi ? 2 : 0)];
    }
    for (std::size_t i = 0; i < f.len; ++i) {
      out += digits[f.data[i] >> 4];
      out += digits[f.data[i] & 0xF];
    }
  }
  if (direction == CandumpDirection::Received) out += " R";
  if (direction == CandumpDirection::Sent) out += " T";
}

}  // namespace rise::hil::io
