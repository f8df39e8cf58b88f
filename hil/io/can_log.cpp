#include "hil/io/can_log.hpp"

#include <cerrno>
#include <cstring>
#include <filesystem>

#include <algorithm>
#include <cstdint>
#include <stdexcept>

#include "hil/io/can_log_binary.hpp"
#include "hil/io/candump_log.hpp"

namespace rise::hil::io {

namespace {

constexpr int kDetectLines = 50;
constexpr size_t kClassicMaxLen = 8;
constexpr size_t kMaxTokens = 96;  // 64 data bytes plus ASC's trailing columns

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

bool starts_with(std::string_view s, std::string_view prefix) {
  return s.size() >= prefix.size() && s.substr(0, prefix.size()) == prefix;
}

bool iequals_prefix(std::string_view s, std::string_view prefix) {
  if (s.size() < prefix.size()) return false;
  for (size_t i = 0; i < prefix.size(); ++i) {
    const auto lower = [](char c) { return c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c; };
    if (lower(s[i]) != lower(prefix[i])) return false;
  }
  return true;
}

// Splits on blanks into tokens (at most kMaxTokens; the rest is dropped).
void tokenize(std::string_view s, std::vector<std::string_view>& out) {
  out.clear();
  size_t i = 0;
  while (i < s.size() && out.size() < kMaxTokens) {
    while (i < s.size() && is_space(s[i])) ++i;
    const size_t start = i;
    while (i < s.size() && !is_space(s[i])) ++i;
    if (i > start) out.push_back(s.substr(start, i - start));
  }
}

int digit_value(char c, int base) {
  int v = -1;
  if (c >= '0' && c <= '9') v = c - '0';
  else if (c >= 'a' && c <= 'f') v = c - 'a' + 10;
  else if (c >= 'A' && c <= 'F') v = c - 'A' + 10;
  return v < base ? v : -1;
}

bool parse_uint(std::string_view text, int base, uint32_t max, uint32_t& out) {
  if (text.empty() || text.size() > 10) return false;
  uint64_t value = 0;
  for (char c : text) {
    const int v = digit_value(c, base);
    if (v < 0) return false;
    value = value * static_cast<uint64_t>(base) + static_cast<uint64_t>(v);
  }
  if (value > max) return false;
  out = static_cast<uint32_t>(value);
  return true;
}

// "12.345" with frac_digits 6 → 12345000 (digits beyond frac_digits are cut).
bool parse_scaled(std::string_view text, int frac_digits, int64_t& out) {
  const size_t dot = text.find('.');
  const std::string_view whole = text.substr(0, dot);
  const std::string_view frac = dot == std::string_view::npos ? std::string_view{} : text.substr(dot + 1);
  if (whole.empty() || whole.size() > 12) return false;
  int64_t value = 0;
  for (char c : whole) {
    if (c < '0' || c > '9') return false;
    value = value * 10 + (c - '0');
  }
  int used = 0;
  for (char c : frac) {
    if (c < '0' || c > '9') return false;
    if (used < frac_digits) {
      value = value * 10 + (c - '0');
      ++used;
    }
  }
  for (; used < frac_digits; ++used) value *= 10;
  out = value;
  return true;
}

// ISO 11898-1 DLC → data length (CAN FD table; classic frames cap at 8).
uint8_t dlc_to_len(uint32_t dlc) {
  constexpr uint8_t kTable[16] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64};
  return dlc < 16 ? kTable[dlc] : 0;
}

bool parse_bytes(const std::vector<std::string_view>& tokens, size_t first, size_t count, int base,
                 CanFrame& frame) {
  if (first + count > tokens.size() || count > frame.data.size()) return false;
  for (size_t i = 0; i < count; ++i) {
    uint32_t b = 0;
    if (!parse_uint(tokens[first + i], base, 0xFF, b)) return false;
    frame.data[i] = static_cast<uint8_t>(b);
  }
  frame.len = static_cast<uint8_t>(count);
  return true;
}

// ASC ids: "6F9" or "18EBFF00x" (29 bit), in the file's base.
bool parse_asc_id(std::string_view text, int base, CanFrame& frame) {
  frame.extended = !text.empty() && (text.back() == 'x' || text.back() == 'X');
  if (frame.extended) text.remove_suffix(1);
  return parse_uint(text, base, frame.extended ? 0x1FFFFFFFu : 0x7FFu, frame.id);
}

// An error frame without an error class (ASC and TRC do not carry one):
// CAN_ERR_DLC bytes, all zero, as linux/can/error.h lays them out.
void make_error_frame(CanFrame& frame) {
  frame.error = true;
  frame.id = 0;
  frame.len = kClassicMaxLen;
}

bool is_direction(std::string_view token) { return token == "Rx" || token == "Tx"; }

std::string_view extension_of(const std::string& path) {
  const size_t dot = path.rfind('.');
  const size_t slash = path.rfind('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return {};
  return std::string_view(path).substr(dot + 1);
}

}  // namespace

const char* to_string(CanLogFormat format) {
  switch (format) {
    case CanLogFormat::Candump: return "candump";
    case CanLogFormat::VectorAsc: return "asc";
    case CanLogFormat::PeakTrc: return "trc";
    case CanLogFormat::VectorBlf: return "blf";
    case CanLogFormat::Pcap: return "pcap";
    case CanLogFormat::Pcapng: return "pcapng";
  }
  return "?";
}

CanLogReader::CanLogReader(const std::string& path) : path_(path), in_(path) {
  if (!in_) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  std::error_code ec;
  size_bytes_ = static_cast<uint64_t>(std::filesystem::file_size(path, ec));
  if (ec) size_bytes_ = 0;
  binary_ = open_binary_can_log(path, format_);
  if (binary_) {
    in_.close();
    return;
  }
  bool known = false;
  std::string text;
  for (int n = 0; n < kDetectLines && !known && std::getline(in_, text); ++n) {
    const std::string_view line = trim(text);
    if (line.empty()) continue;
    if (line.front() == '(' && parse_candump_line(line).ok()) {
      format_ = CanLogFormat::Candump;
      known = true;
    } else if (line.front() == ';') {
      format_ = CanLogFormat::PeakTrc;
      known = true;
    } else if (starts_with(line, "date ") || starts_with(line, "base ") ||
               iequals_prefix(line, "begin triggerblock") || starts_with(line, "// version") ||
               starts_with(line, "internal events logged")) {
      format_ = CanLogFormat::VectorAsc;
      known = true;
    }
  }
  if (!known) {
    const std::string_view ext = extension_of(path);
    if (ext == "log") format_ = CanLogFormat::Candump;
    else if (ext == "asc" || ext == "ASC") format_ = CanLogFormat::VectorAsc;
    else if (ext == "trc" || ext == "TRC") format_ = CanLogFormat::PeakTrc;
    else throw std::runtime_error(path + ":1: format: not a candump, ASC, TRC, BLF, pcap or pcapng log");
  }
  rewind();
}

CanLogReader::~CanLogReader() = default;
CanLogReader::CanLogReader(CanLogReader&&) noexcept = default;
CanLogReader& CanLogReader::operator=(CanLogReader&&) noexcept = default;

uint64_t CanLogReader::bytes_consumed() const {
  if (binary_) return binary_->bytes_consumed();
  return stream_read_ - (block_end_ - block_begin_);
}

void CanLogReader::count_malformed(int line) {
  ++malformed_count_;
  if (malformed_lines_.size() < kMaxMalformedLines) malformed_lines_.push_back(line);
}

void CanLogReader::reset_state() {
  line_ = 0;
  malformed_count_ = 0;
  malformed_lines_.clear();
  asc_decimal_ = false;
  asc_relative_ = false;
  asc_last_us_ = 0;
  trc_version_ = 0;
  trc_columns_.clear();
}

void CanLogReader::rewind() {
  if (binary_) {
    binary_->rewind();
    reset_state();
    return;
  }
  in_.clear();
  in_.seekg(0);
  block_begin_ = block_end_ = 0;
  stream_read_ = 0;
  eof_ = false;
  reset_state();
}

bool CanLogReader::next_line(std::string_view& line) {
  constexpr std::size_t kBlock = 1 << 20;
  for (;;) {
    const char* begin = block_.data() + block_begin_;
    const std::size_t left = block_end_ - block_begin_;
    if (const void* nl = left ? std::memchr(begin, '\n', left) : nullptr) {
      const auto n = static_cast<std::size_t>(static_cast<const char*>(nl) - begin);
      line = std::string_view(begin, n);
      block_begin_ += n + 1;
      return true;
    }
    if (eof_) {
      if (left == 0) return false;
      line = std::string_view(begin, left);  // last line without a newline
      block_begin_ = block_end_;
      return true;
    }
    // Keep the partial line, grow for lines longer than a block, read more.
    if (left > 0) std::memmove(block_.data(), begin, left);  // an empty block_'s data() may be null
    block_begin_ = 0;
    block_end_ = left;
    if (block_.size() < left + kBlock) block_.resize(left + kBlock);
    in_.read(block_.data() + block_end_, static_cast<std::streamsize>(block_.size() - block_end_));
    block_end_ += static_cast<std::size_t>(in_.gcount());
    stream_read_ += static_cast<uint64_t>(in_.gcount());
    if (!in_) eof_ = true;
  }
}

bool CanLogReader::next(CanLogRecord& record) {
  if (binary_) {
    for (;;) {
      switch (binary_->next(record)) {
        case BinaryCanLog::Result::Frame: return true;
        case BinaryCanLog::Result::End: return false;
        case BinaryCanLog::Result::Malformed: count_malformed(record.line); break;
      }
    }
  }
  if (format_ == CanLogFormat::Candump) {
    // The shape candump -l writes, parsed in place; anything else (and a
    // line cut by the block's end) takes the general path below.
    std::string_view interface;
    const char* begin = block_.data() + block_begin_;
    if (const char* after = parse_candump_fast(begin, block_.data() + block_end_, record.frame, interface, record.tx)) {
      block_begin_ += static_cast<std::size_t>(after - begin);
      record.line = ++line_;
      if (record.channel != interface) record.channel.assign(interface);
      return true;
    }
  }
  std::string_view text;
  while (next_line(text)) {
    ++line_;
    record.channel.clear();
    record.tx = false;
    record.line = line_;
    const LineResult result = parse_line(trim(text), record);
    if (result == LineResult::Frame) return true;
    if (result == LineResult::Malformed) count_malformed(line_);
  }
  return false;
}

CanLogReader::LineResult CanLogReader::parse_line(std::string_view line, CanLogRecord& record) {
  if (line.empty()) return LineResult::Skip;
  switch (format_) {
    case CanLogFormat::Candump: {
      std::string_view interface;
      if (parse_candump_line(line, record.frame, interface, &record.tx) != CandumpError::None)
        return LineResult::Malformed;
      record.channel.assign(interface);
      return LineResult::Frame;
    }
    case CanLogFormat::VectorAsc: record.frame = CanFrame{}; return parse_asc(line, record);
    case CanLogFormat::PeakTrc: record.frame = CanFrame{}; return parse_trc(line, record);
    case CanLogFormat::VectorBlf:
    case CanLogFormat::Pcap:
    case CanLogFormat::Pcapng: break;  // binary: never line by line
  }
  return LineResult::Malformed;
}

// Vector ASC, as Vector's "CAN Log File Format" and python-can's asc.py read it.
CanLogReader::LineResult CanLogReader::parse_asc(std::string_view line, CanLogRecord& record) {
  if (starts_with(line, "//") || starts_with(line, "date ") || iequals_prefix(line, "begin triggerblock") ||
      iequals_prefix(line, "end triggerblock") || starts_with(line, "internal events logged") ||
      starts_with(line, "no internal events logged")) {
    return LineResult::Skip;
  }
  std::vector<std::string_view> tok;
  tokenize(line, tok);
  if (tok[0] == "base") {  // "base hex  timestamps absolute"
    for (size_t i = 1; i < tok.size(); ++i) {
      if (tok[i] == "dec") asc_decimal_ = true;
      if (tok[i] == "hex") asc_decimal_ = false;
      if (tok[i] == "relative") asc_relative_ = true;
      if (tok[i] == "absolute") asc_relative_ = false;
    }
    return LineResult::Skip;
  }
  int64_t t_us = 0;
  if (tok.size() < 2 || !parse_scaled(tok[0], 6, t_us)) return LineResult::Malformed;
  // Relative stamps count from the previous event, whatever its kind.
  if (asc_relative_) {
    if (t_us > INT64_MAX - asc_last_us_) return LineResult::Malformed;
    t_us = asc_last_us_ += t_us;
  }
  record.frame.timestamp_us = t_us;
  const int base = asc_decimal_ ? 10 : 16;
  CanFrame& f = record.frame;

  if (tok[1] == "Start") return LineResult::Skip;  // "Start of measurement"
  if (tok[1] == "CAN") {                           // "CAN 1 Status:chip status error active"
    for (std::string_view t : tok) {
      if (starts_with(t, "Status:")) return LineResult::Skip;
    }
    return LineResult::Malformed;
  }
  if (tok[1] == "CANFD") {
    // CANFD ch dir id [name] brs esi dlc data_length data... (then timing columns),
    // or CANFD ch dir ErrorFrame ...
    if (tok.size() < 5 || !is_direction(tok[3])) return LineResult::Malformed;
    record.channel = std::string(tok[2]);
    record.tx = tok[3] == "Tx";
    if (tok[4] == "ErrorFrame") {
      make_error_frame(f);
      return LineResult::Frame;
    }
    if (!parse_asc_id(tok[4], base, f)) return LineResult::Malformed;
    size_t i = 5;
    if (i < tok.size() && tok[i] != "0" && tok[i] != "1") ++i;  // symbolic message name
    if (i + 4 > tok.size()) return LineResult::Malformed;
    uint32_t brs = 0, esi = 0, dlc = 0, data_length = 0;
    if (!parse_uint(tok[i], 2, 1, brs) || !parse_uint(tok[i + 1], 2, 1, esi) ||
        !parse_uint(tok[i + 2], 16, 15, dlc) || !parse_uint(tok[i + 3], 10, 64, data_length)) {
      return LineResult::Malformed;
    }
    if (data_length == 0 && dlc > 0) {
      // A classic remote frame logged as a CANFD record (as python-can reads it).
      if (dlc > kClassicMaxLen) return LineResult::Malformed;
      f.remote = true;
      f.len = static_cast<uint8_t>(dlc);
      return LineResult::Frame;
    }
    if (!is_fd_length(data_length) || !parse_bytes(tok, i + 4, data_length, base, f)) {
      return LineResult::Malformed;
    }
    f.fd = true;
    f.brs = brs != 0;
    f.esi = esi != 0;
    return LineResult::Frame;
  }

  // Classic: ch id [Rx|Tx] d dlc bytes... | ch id [Rx|Tx] r [dlc] | ch ErrorFrame ...
  uint32_t channel = 0;
  if (!parse_uint(tok[1], 10, 0xFFFF, channel)) return LineResult::Malformed;
  record.channel = std::string(tok[1]);
  if (tok.size() < 3) return LineResult::Malformed;
  if (tok[2] == "Statistic:" || tok[2] == "J1939TP") return LineResult::Skip;
  if (tok[2] == "ErrorFrame") {
    make_error_frame(f);
    return LineResult::Frame;
  }
  if (!parse_asc_id(tok[2], base, f)) return LineResult::Malformed;
  size_t i = 3;
  if (i < tok.size() && is_direction(tok[i])) record.tx = tok[i++] == "Tx";
  if (i >= tok.size()) return LineResult::Malformed;
  if (tok[i] == "r") {
    f.remote = true;
    uint32_t dlc = 0;
    if (i + 1 < tok.size() && parse_uint(tok[i + 1], 16, 15, dlc)) {
      f.len = static_cast<uint8_t>(std::min<uint32_t>(dlc, kClassicMaxLen));
    }
    return LineResult::Frame;
  }
  if (tok[i] != "d" || i + 1 >= tok.size()) return LineResult::Malformed;
  uint32_t dlc = 0;
  if (!parse_uint(tok[i + 1], 16, 15, dlc)) return LineResult::Malformed;
  // DLC 9..15 on a classic frame still means 8 bytes (ISO 11898-1).
  const size_t n = std::min<size_t>(dlc, kClassicMaxLen);
  return parse_bytes(tok, i + 2, n, base, f) ? LineResult::Frame : LineResult::Malformed;
}

// PEAK "PCAN-Trace File Format" 1.0 .. 2.1; 2.x lines follow the $COLUMNS header.
CanLogReader::LineResult CanLogReader::parse_trc(std::string_view line, CanLogRecord& record) {
  if (line.front() == ';') {
    if (starts_with(line, ";$FILEVERSION=")) {
      const std::string_view v = trim(line.substr(14));
      const size_t dot = v.find('.');
      uint32_t major = 0, minor = 0;
      if (dot == std::string_view::npos || !parse_uint(v.substr(0, dot), 10, 9, major) ||
          !parse_uint(v.substr(dot + 1), 10, 9, minor)) {
        return LineResult::Malformed;
      }
      trc_version_ = static_cast<int>(major * 10 + minor);
    } else if (starts_with(line, ";$COLUMNS=")) {
      trc_columns_.clear();
      for (char c : line.substr(10)) {
        if (c != ',' && !is_space(c)) trc_columns_ += c;
      }
    }
    return LineResult::Skip;
  }
  std::vector<std::string_view> tok;
  tokenize(line, tok);
  CanFrame& f = record.frame;

  if (trc_version_ < 20 && !tok.empty() && tok[0].back() == ')') {
    // 1.0: N) time_ms id dlc data   1.1: N) time_ms dir id dlc data
    // 1.2: N) time_ms bus dir id dlc data   1.3: N) time_ms bus dir id - dlc data
    if (tok.size() < 4 || !parse_scaled(tok[1], 3, f.timestamp_us)) return LineResult::Malformed;
    size_t i = 2;
    if (tok.size() > 3 && is_direction(tok[3])) record.channel = std::string(tok[i++]);
    if (is_direction(tok[i])) {
      record.tx = tok[i++] == "Tx";
    } else if (tok[i] == "Warng" || tok[i] == "Error") {
      return LineResult::Skip;  // bus status events, not frames
    }
    if (i + 1 >= tok.size()) return LineResult::Malformed;
    const std::string_view id = tok[i++];
    f.extended = id.size() > 4;
    if (!parse_uint(id, 16, f.extended ? 0x1FFFFFFFu : 0x7FFu, f.id)) return LineResult::Malformed;
    if (tok[i] == "-") ++i;
    uint32_t dlc = 0;
    if (i >= tok.size() || !parse_uint(tok[i++], 10, 8, dlc)) return LineResult::Malformed;
    if (i < tok.size() && tok[i] == "RTR") {
      f.remote = true;
      f.len = static_cast<uint8_t>(dlc);
      return LineResult::Frame;
    }
    return parse_bytes(tok, i, dlc, 16, f) ? LineResult::Frame : LineResult::Malformed;
  }

  // 2.x: columns N number, O offset ms, T type, B bus, I id, d direction,
  // R reserved, L DLC, l data length, D data (the rest of the line).
  std::string_view columns = trc_columns_;
  if (columns.empty()) columns = trc_version_ == 20 ? "NOTIdlD" : "NOTBIdRLD";
  std::string_view type, id, dlc_text, length_text;
  size_t data_at = tok.size();
  bool have_time = false;
  size_t i = 0;
  for (char c : columns) {
    if (c == 'D') {
      data_at = i;
      break;
    }
    if (i >= tok.size()) break;
    const std::string_view t = tok[i++];
    switch (c) {
      case 'O': have_time = parse_scaled(t, 3, f.timestamp_us); break;
      case 'T': type = t; break;
      case 'B': record.channel = std::string(t); break;
      case 'I': id = t; break;
      case 'd': record.tx = t == "Tx"; break;
      case 'L': dlc_text = t; break;
      case 'l': length_text = t; break;
      default: break;
    }
  }
  if (!have_time || type.empty()) return LineResult::Malformed;
  if (type == "ER") {
    make_error_frame(f);
    return LineResult::Frame;
  }
  const bool classic = type == "DT" || type == "RR";
  const bool fd = type == "FD" || type == "FB" || type == "FE" || type == "BI";
  if (!classic && !fd) return LineResult::Skip;  // ST status, EC error counters, EV events
  f.extended = id.size() > 4;
  if (!parse_uint(id, 16, f.extended ? 0x1FFFFFFFu : 0x7FFu, f.id)) return LineResult::Malformed;
  uint32_t dlc = 0, length = 0;
  if (!length_text.empty()) {
    if (!parse_uint(length_text, 10, 64, length)) return LineResult::Malformed;
  } else {
    if (!parse_uint(dlc_text, 10, 15, dlc)) return LineResult::Malformed;
    length = fd ? dlc_to_len(dlc) : std::min<uint32_t>(dlc, kClassicMaxLen);
  }
  if (type == "RR") {
    if (length > kClassicMaxLen) return LineResult::Malformed;
    f.remote = true;
    f.len = static_cast<uint8_t>(length);
    return LineResult::Frame;
  }
  if (fd) {
    if (!is_fd_length(length)) return LineResult::Malformed;
    f.fd = true;
    f.brs = type == "FB" || type == "BI";
    f.esi = type == "FE" || type == "BI";
  } else if (length > kClassicMaxLen) {
    return LineResult::Malformed;
  }
  return parse_bytes(tok, data_at, length, 16, f) ? LineResult::Frame : LineResult::Malformed;
}

std::vector<CanLogRecord> read_can_log(const std::string& path) {
  CanLogReader reader(path);
  std::vector<CanLogRecord> records;
  CanLogRecord record;
  while (reader.next(record)) records.push_back(std::move(record));
  return records;
}

}  // namespace rise::hil::io
