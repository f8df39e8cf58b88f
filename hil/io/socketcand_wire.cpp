#include "hil/io/socketcand_wire.hpp"

#include <algorithm>
#include <cstring>

namespace rise::hil::io::socketcand {

namespace {

constexpr uint8_t kFlagBrs = 0x01;  // CANFD_BRS in linux/can.h
constexpr uint8_t kFlagEsi = 0x02;  // CANFD_ESI
constexpr size_t kMaxTokens = 4 + 64 + 4;

// Appends to a MessageBuffer; finish() is 0 if anything did not fit.
class Writer {
 public:
  explicit Writer(MessageBuffer& out) : out_(out) {}

  void put(char c) {
    if (length_ < out_.size()) {
      out_[length_++] = c;
    } else {
      overflow_ = true;
    }
  }
  void text(std::string_view s) {
    for (char c : s) put(c);
  }
  void hex(uint32_t value, int min_digits) {
    char digits[8];
    int n = 0;
    do {
      digits[n++] = kHex[value & 0xF];
      value >>= 4;
    } while (value != 0 && n < 8);
    for (int i = n; i < min_digits; ++i) put('0');
    while (n > 0) put(digits[--n]);
  }
  void decimal(uint64_t value) {
    char digits[20];
    int n = 0;
    do {
      digits[n++] = static_cast<char>('0' + value % 10);
      value /= 10;
    } while (value != 0 && n < 20);
    while (n > 0) put(digits[--n]);
  }
  void byte(uint8_t b) {
    put(kHex[b >> 4]);
    put(kHex[b & 0xF]);
  }
  void id(const CanFrame& frame) { hex(frame.id, frame.extended ? 8 : 3); }
  // SECS.USECS as socketcand prints it ("%ld.%06ld").
  void timestamp(int64_t us) {
    if (us < 0) us = 0;
    decimal(static_cast<uint64_t>(us / 1'000'000));
    put('.');
    const auto fraction = static_cast<uint32_t>(us % 1'000'000);
    for (uint32_t scale = 100'000; scale > 0; scale /= 10) {
      put(static_cast<char>('0' + (fraction / scale) % 10));
    }
  }
  size_t finish() const { return overflow_ ? 0 : length_; }

 private:
  static constexpr char kHex[] = "0123456789ABCDEF";
  MessageBuffer& out_;
  size_t length_ = 0;
  bool overflow_ = false;
};

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

std::optional<uint32_t> parse_hex(std::string_view s, size_t max_digits) {
  if (s.empty() || s.size() > max_digits) return std::nullopt;
  uint32_t value = 0;
  for (char c : s) {
    const int v = hex_value(c);
    if (v < 0) return std::nullopt;
    value = (value << 4) | static_cast<uint32_t>(v);
  }
  return value;
}

std::optional<uint32_t> parse_decimal(std::string_view s, size_t max_digits) {
  if (s.empty() || s.size() > max_digits) return std::nullopt;
  uint32_t value = 0;
  for (char c : s) {
    if (c < '0' || c > '9') return std::nullopt;
    value = value * 10 + static_cast<uint32_t>(c - '0');
  }
  return value;
}

// 1..8 hex digits; 8 digits (socketcand's rule) or a value above 7FF is a 29-bit id.
bool parse_id(std::string_view s, CanFrame& frame) {
  const auto id = parse_hex(s, 8);
  if (!id || *id > 0x1FFFFFFF) return false;
  frame.id = *id;
  frame.extended = s.size() == 8 || *id > 0x7FF;
  return true;
}

// SECS[.FRACTION] with up to 6 fraction digits → µs since the epoch.
std::optional<int64_t> parse_timestamp(std::string_view s) {
  const size_t dot = s.find('.');
  const auto secs = parse_decimal(s.substr(0, dot), 10);
  if (!secs) return std::nullopt;
  int64_t us = static_cast<int64_t>(*secs) * 1'000'000;
  if (dot != std::string_view::npos) {
    const std::string_view fraction = s.substr(dot + 1);
    const auto value = parse_decimal(fraction, 6);
    if (!value) return std::nullopt;
    int64_t scaled = *value;
    for (size_t i = fraction.size(); i < 6; ++i) scaled *= 10;
    us += scaled;
  }
  return us;
}

// Concatenated bytes "0A1B2C" (what socketcand writes).
bool parse_packed_data(std::string_view s, size_t max_len, CanFrame& frame) {
  if (s.size() % 2 != 0 || s.size() / 2 > max_len) return false;
  for (size_t i = 0; i < s.size(); i += 2) {
    const int hi = hex_value(s[i]);
    const int lo = hex_value(s[i + 1]);
    if (hi < 0 || lo < 0) return false;
    frame.data[i / 2] = static_cast<uint8_t>(hi * 16 + lo);
  }
  frame.len = static_cast<uint8_t>(s.size() / 2);
  return true;
}

// One byte per token, 1 or 2 hex digits ("0a 1b 2c" or python-can's "a 1b 2c").
bool parse_spaced_data(std::span<const std::string_view> tokens, size_t max_len, CanFrame& frame) {
  if (tokens.size() > max_len) return false;
  for (size_t i = 0; i < tokens.size(); ++i) {
    const auto b = parse_hex(tokens[i], 2);
    if (!b) return false;
    frame.data[i] = static_cast<uint8_t>(*b);
  }
  frame.len = static_cast<uint8_t>(tokens.size());
  return true;
}

// DATA after the timestamp of frame/fdframe: packed (socketcand's code) or
// one token per byte (protocol.md's example).
bool parse_data(std::span<const std::string_view> tokens, size_t max_len, CanFrame& frame) {
  if (tokens.empty()) {
    frame.len = 0;
    return true;
  }
  if (tokens.size() == 1 && tokens[0].size() != 1) {
    return parse_packed_data(tokens[0], max_len, frame);
  }
  return parse_spaced_data(tokens, max_len, frame);
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r' || s.front() == '\n')) {
    s.remove_prefix(1);
  }
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r' || s.back() == '\n')) {
    s.remove_suffix(1);
  }
  return s;
}

Message malformed(std::string_view inner) {
  Message m;
  m.kind = MessageKind::Malformed;
  m.text = inner;
  return m;
}

Message decode_received(std::span<const std::string_view> t, std::string_view inner) {
  Message m;
  m.kind = MessageKind::Frame;
  CanFrame& f = m.frame;
  const std::string_view command = t[0];
  if (command == "frame" || command == "fdframe") {
    const bool fd = command == "fdframe";
    const size_t head = fd ? 4 : 3;
    if (t.size() < head || !parse_id(t[1], f)) return malformed(inner);
    if (fd) {
      const auto flags = parse_hex(t[2], 2);
      if (!flags) return malformed(inner);
      f.fd = true;
      f.brs = (*flags & kFlagBrs) != 0;
      f.esi = (*flags & kFlagEsi) != 0;
    }
    const auto ts = parse_timestamp(t[head - 1]);
    if (!ts || !parse_data(t.subspan(head), fd ? 64 : 8, f)) return malformed(inner);
    if (fd && !is_fd_length(f.len)) return malformed(inner);
    f.timestamp_us = *ts;
    return m;
  }
  if (command == "rtr") {
    if (t.size() != 4 || !parse_id(t[1], f)) return malformed(inner);
    const auto ts = parse_timestamp(t[2]);
    const auto dlc = parse_hex(t[3], 1);
    if (!ts || !dlc || *dlc > 8) return malformed(inner);
    f.remote = true;
    f.len = static_cast<uint8_t>(*dlc);
    f.timestamp_us = *ts;
    return m;
  }
  // "error": a bus error frame when it carries a class and a time, else a
  // protocol error reply.
  if (t.size() == 3) {
    const auto error_class = parse_hex(t[1], 8);
    const auto ts = parse_timestamp(t[2]);
    if (error_class && ts && *error_class <= 0x1FFFFFFF) {
      f.error = true;
      f.id = *error_class;
      f.timestamp_us = *ts;
      return m;
    }
  }
  m.kind = MessageKind::Error;
  m.text = trim(inner.substr(inner.find("error") + 5));
  return m;
}

Message decode_send(std::span<const std::string_view> t, std::string_view inner) {
  Message m;
  m.kind = MessageKind::Send;
  CanFrame& f = m.frame;
  const std::string_view command = t[0];
  if (t.size() < 3 || !parse_id(t[1], f)) return malformed(inner);
  if (command == "send") {
    // socketcand scans the DLC with %hhu, the brief of this protocol says hex:
    // for 0..8 both read the same.
    const auto dlc = parse_hex(t[2], 1);
    if (!dlc || *dlc > 8 || t.size() != 3 + *dlc) return malformed(inner);
    if (!parse_spaced_data(t.subspan(3), 8, f)) return malformed(inner);
    return m;
  }
  if (command == "sendrtr") {
    const auto dlc = parse_hex(t[2], 1);
    if (t.size() != 3 || !dlc || *dlc > 8) return malformed(inner);
    f.remote = true;
    f.len = static_cast<uint8_t>(*dlc);
    return m;
  }
  // fdsend ID FLAGS LEN B0 ...: flags hex, len decimal (state_raw.c: "%x %hhx %hhu").
  if (t.size() < 4) return malformed(inner);
  const auto flags = parse_hex(t[2], 2);
  const auto len = parse_decimal(t[3], 2);
  if (!flags || !len || !is_fd_length(*len) || t.size() != 4 + *len) return malformed(inner);
  if (!parse_spaced_data(t.subspan(4), 64, f)) return malformed(inner);
  f.fd = true;
  f.brs = (*flags & kFlagBrs) != 0;
  f.esi = (*flags & kFlagEsi) != 0;
  return m;
}

}  // namespace

size_t format_frame(const CanFrame& frame, int64_t timestamp_us, MessageBuffer& out) {
  if (!is_well_formed(frame)) return 0;
  Writer w(out);
  if (frame.error) {
    w.text("< error ");
    w.hex(frame.id, 3);
    w.put(' ');
    w.timestamp(timestamp_us);
    w.text(" >");
    return w.finish();
  }
  if (frame.remote) {
    w.text("< rtr ");
    w.id(frame);
    w.put(' ');
    w.timestamp(timestamp_us);
    w.put(' ');
    w.decimal(frame.len);
    w.text(" >");
    return w.finish();
  }
  if (frame.fd) {
    w.text("< fdframe ");
    w.id(frame);
    w.put(' ');
    w.hex(static_cast<uint32_t>((frame.brs ? kFlagBrs : 0) | (frame.esi ? kFlagEsi : 0)), 2);
  } else {
    w.text("< frame ");
    w.id(frame);
  }
  w.put(' ');
  w.timestamp(timestamp_us);
  w.put(' ');
  for (size_t i = 0; i < frame.len; ++i) w.byte(frame.data[i]);
  w.text(" >");
  return w.finish();
}

size_t format_send(const CanFrame& frame, MessageBuffer& out) {
  if (frame.error || !is_well_formed(frame)) return 0;
  Writer w(out);
  if (frame.remote) {
    w.text("< sendrtr ");
    w.id(frame);
    w.put(' ');
    w.decimal(frame.len);
    w.text(" >");
    return w.finish();
  }
  if (frame.fd) {
    w.text("< fdsend ");
    w.id(frame);
    w.put(' ');
    w.hex(static_cast<uint32_t>((frame.brs ? kFlagBrs : 0) | (frame.esi ? kFlagEsi : 0)), 1);
    w.put(' ');
    w.decimal(frame.len);
  } else {
    w.text("< send ");
    w.id(frame);
    w.put(' ');
    w.hex(frame.len, 1);
  }
  for (size_t i = 0; i < frame.len; ++i) {
    w.put(' ');
    w.byte(frame.data[i]);
  }
  w.text(" >");
  return w.finish();
}

Message parse_message(std::string_view message) {
  if (message.size() < 2 || message.front() != '<' || message.back() != '>') {
    return malformed(message);
  }
  const std::string_view inner = trim(message.substr(1, message.size() - 2));
  std::array<std::string_view, kMaxTokens> storage;
  size_t count = 0;
  for (size_t i = 0; i < inner.size();) {
    if (inner[i] == ' ' || inner[i] == '\t' || inner[i] == '\r' || inner[i] == '\n') {
      ++i;
      continue;
    }
    size_t j = i;
    while (j < inner.size() && inner[j] != ' ' && inner[j] != '\t' && inner[j] != '\r' && inner[j] != '\n') ++j;
    if (count == storage.size()) return malformed(inner);
    storage[count++] = inner.substr(i, j - i);
    i = j;
  }
  Message m;
  m.text = inner;
  if (count == 0) return malformed(inner);
  const std::span<const std::string_view> t(storage.data(), count);
  const std::string_view command = t[0];
  if (count == 1) {
    if (command == "hi") m.kind = MessageKind::Hi;
    if (command == "ok") m.kind = MessageKind::Ok;
    if (command == "echo") m.kind = MessageKind::Echo;
    if (command == "rawmode") m.kind = MessageKind::Rawmode;
  }
  if (m.kind != MessageKind::Other) return m;
  if (command == "open") {
    if (count != 2) return malformed(inner);
    m.kind = MessageKind::Open;
    m.text = t[1];
    return m;
  }
  if (command == "frame" || command == "fdframe" || command == "rtr" || command == "error") {
    return decode_received(t, inner);
  }
  if (command == "send" || command == "fdsend" || command == "sendrtr") {
    return decode_send(t, inner);
  }
  return m;
}

std::span<char> StreamParser::free_space() {
  if (begin_ > 0) {
    std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
    end_ -= begin_;
    begin_ = 0;
  }
  if (end_ == buffer_.size()) {
    skipped_ += end_;
    end_ = 0;
  }
  return {buffer_.data() + end_, buffer_.size() - end_};
}

void StreamParser::commit(size_t n) { end_ = std::min(end_ + n, buffer_.size()); }

std::optional<std::string_view> StreamParser::next() {
  const char* b = buffer_.data();
  while (begin_ < end_) {
    const char* open = static_cast<const char*>(std::memchr(b + begin_, '<', end_ - begin_));
    if (open == nullptr) {
      skipped_ += end_ - begin_;
      begin_ = end_ = 0;
      return std::nullopt;
    }
    const auto start = static_cast<size_t>(open - b);
    skipped_ += start - begin_;
    begin_ = start;
    size_t i = start + 1;
    while (i < end_ && b[i] != '>' && b[i] != '<') ++i;
    if (i == end_) {
      if (begin_ == 0 && end_ == buffer_.size()) {  // no room left to complete it
        skipped_ += end_;
        begin_ = end_ = 0;
      }
      return std::nullopt;
    }
    if (b[i] == '<') {  // an opened message cut by a new one: drop the stub
      skipped_ += i - begin_;
      begin_ = i;
      continue;
    }
    begin_ = i + 1;
    return std::string_view(b + start, i - start + 1);
  }
  return std::nullopt;
}

void StreamParser::clear() { begin_ = end_ = 0; }

}  // namespace rise::hil::io::socketcand
