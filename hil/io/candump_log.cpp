#include "hil/io/candump_log.hpp"

#include <cstdio>

namespace rise::io {
namespace {

constexpr uint32_t kErrFlag = 0x20000000u;  // CAN_ERR_FLAG in <linux/can.h>
constexpr uint32_t kEffMask = 0x1FFFFFFFu;

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

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

}  // namespace

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

CandumpParse parse_candump_line(std::string_view line) {
  CandumpParse r;
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r' || line.back() == ' ')) line.remove_suffix(1);
  while (!line.empty() && line.front() == ' ') line.remove_prefix(1);
  if (line.empty()) return r.error = CandumpError::Empty, r;
  std::string_view rest;
  const std::optional<int64_t> time_us = parse_log_time(line, &rest);
  if (!time_us) return r.error = CandumpError::NoTimestamp, r;
  r.record.frame.timestamp_us = *time_us;

  while (!rest.empty() && rest.front() == ' ') rest.remove_prefix(1);
  const auto space = rest.find(' ');
  if (space == std::string_view::npos || space == 0) return r.error = CandumpError::NoInterface, r;
  r.record.interface = std::string(rest.substr(0, space));
  rest = rest.substr(space + 1);
  while (!rest.empty() && rest.front() == ' ') rest.remove_prefix(1);
  // After the frame candump -x and python-can write the direction (" R" /
  // " T"); anything else there is ignored.
  if (const auto end = rest.find(' '); end != std::string_view::npos) {
    std::string_view after = rest.substr(end);
    while (!after.empty() && after.front() == ' ') after.remove_prefix(1);
    r.record.tx = after == "T" || after == "t";
    rest = rest.substr(0, end);
  }

  const auto hash = rest.find('#');
  if (hash == std::string_view::npos) return r.error = CandumpError::BadId, r;
  CanFrame& f = r.record.frame;
  uint32_t id = 0;
  if (!parse_hex(rest.substr(0, hash), id)) return r.error = CandumpError::BadId, r;
  if (hash == 3) {
    if (id > 0x7FF) return r.error = CandumpError::BadId, r;
  } else if (hash == 8) {
    f.error = (id & kErrFlag) != 0;  // then the id holds the error class
    f.extended = !f.error;
    id &= kEffMask;
  } else {
    return r.error = CandumpError::BadId, r;
  }
  f.id = id;

  std::string_view data = rest.substr(hash + 1);
  if (!data.empty() && data.front() == '#') {  // CAN FD: flags nibble first
    data.remove_prefix(1);
    if (data.empty()) return r.error = CandumpError::BadData, r;
    const int flags = hex_value(data.front());
    if (flags < 0) return r.error = CandumpError::BadData, r;
    f.fd = true;
    f.brs = flags & 0x1;  // CANFD_BRS
    f.esi = flags & 0x2;  // CANFD_ESI
    data.remove_prefix(1);
    if (!parse_data(data, f, 64)) return r.error = CandumpError::TooLong, r;
    if (!is_fd_length(f.len)) return r.error = CandumpError::BadData, r;
    return r;
  }
  if (!data.empty() && (data.front() == 'R' || data.front() == 'r')) {
    f.remote = true;
    f.len = 0;
    if (data.size() == 2) {
      const int len = hex_value(data[1]);
      if (len < 0 || len > 8) return r.error = CandumpError::BadData, r;
      f.len = static_cast<uint8_t>(len);
    } else if (data.size() > 2) {
      return r.error = CandumpError::BadData, r;
    }
    return r;
  }
  if (!parse_data(data, f, 8)) return r.error = data.size() > 16 ? CandumpError::TooLong : CandumpError::BadData, r;
  return r;
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

}  // namespace rise::io
