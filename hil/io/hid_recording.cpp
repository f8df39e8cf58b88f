#include "hil/io/hid_recording.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <stdexcept>
#include <utility>

namespace rise::hil::io {
namespace {

constexpr char kHex[] = "0123456789abcdef";

void append_unsigned(std::string& out, uint64_t value, int width = 0) {
  char text[24];
  const auto r = std::to_chars(text, text + sizeof text, value);
  const auto digits = static_cast<int>(r.ptr - text);
  for (int i = digits; i < width; ++i) out += '0';
  out.append(text, static_cast<std::size_t>(digits));
}

void append_hex_bytes(std::string& out, std::span<const uint8_t> bytes) {
  for (const uint8_t b : bytes) {
    out += ' ';
    out += kHex[b >> 4];
    out += kHex[b & 15];
  }
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r' || s.back() == '\n'))
    s.remove_suffix(1);
  return s;
}

// Takes the blank-separated words off the front of `rest`, one per call
// (empty at the end).
std::string_view next_word(std::string_view& rest) {
  auto blank = [](char c) { return c == ' ' || c == '\t'; };
  std::size_t i = 0;
  while (i < rest.size() && blank(rest[i])) ++i;
  std::size_t j = i;
  while (j < rest.size() && !blank(rest[j])) ++j;
  const std::string_view word(rest.data() + i, j - i);
  rest.remove_prefix(j);
  return word;
}

template <typename T>
bool parse_number(std::string_view text, T& value, int base = 10) {
  if (text.empty()) return false;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), value, base);
  return r.ec == std::errc() && r.ptr == text.data() + text.size();
}

// "SEC.USEC" with exactly six digits of microseconds, as hid-recorder writes it.
bool parse_time(std::string_view text, int64_t& us) {
  const auto dot = text.find('.');
  if (dot == std::string_view::npos || dot == 0 || dot > 12 || text.size() - dot - 1 != 6) return false;
  int64_t sec = 0, usec = 0;
  if (!parse_number(text.substr(0, dot), sec) || !parse_number(text.substr(dot + 1), usec)) return false;
  us = sec * 1'000'000 + usec;
  return true;
}

// "LEN HEX..." into `out`; nullptr, or what is wrong.
const char* parse_length_and_bytes(std::string_view rest, std::size_t max, std::vector<uint8_t>& out) {
  std::size_t length = 0;
  if (!parse_number(next_word(rest), length)) return "missing the length";
  if (length > max) return "longer than a HID report can be";
  out.clear();
  for (std::string_view w = next_word(rest); !w.empty(); w = next_word(rest)) {
    unsigned byte = 0;
    if (w.size() > 2 || !parse_number(w, byte, 16)) return "a byte that is not one or two hex digits";
    if (out.size() == max) return "longer than a HID report can be";
    out.push_back(static_cast<uint8_t>(byte));
  }
  if (out.size() != length) return "the length does not match the bytes after it";
  return nullptr;
}

// The comments our recordings add (hid_recording.hpp).
enum class Mark { None, Plugged, Start, Unplugged, End, BadTime };

Mark parse_mark(std::string_view line, int64_t& t_us) {
  struct Prefix {
    std::string_view text;
    Mark mark;
  };
  constexpr Prefix prefixes[] = {{"# plugged at ", Mark::Plugged},
                                 {"# start ", Mark::Start},
                                 {"# unplugged at ", Mark::Unplugged},
                                 {"# end at ", Mark::End}};
  for (const Prefix& p : prefixes) {
    if (!line.starts_with(p.text)) continue;
    std::string_view rest = line.substr(p.text.size());
    std::string_view time = rest.substr(0, std::min(rest.find_first_of(" :"), rest.size()));
    return parse_time(time, t_us) ? p.mark : Mark::BadTime;
  }
  return Mark::None;
}

}  // namespace

void append_hid_time(std::string& out, int64_t us, int width) {
  us = std::max<int64_t>(us, 0);
  append_unsigned(out, static_cast<uint64_t>(us / 1'000'000), width);
  out += '.';
  append_unsigned(out, static_cast<uint64_t>(us % 1'000'000), 6);
}

void append_hid_event(std::string& out, int64_t since_first_us, std::span<const uint8_t> report) {
  out += "E: ";
  append_hid_time(out, since_first_us, 6);
  out += ' ';
  append_unsigned(out, report.size());
  append_hex_bytes(out, report);
}

HidRecordingWriter::HidRecordingWriter(const std::string& path, std::string_view source)
    : file_(path, "HID recording") {
  line_.reserve(64 + 3 * max_hid_report_bytes);
  line_ = "# rise-hild hid recording v1: source '";
  line_ += source;
  line_ += "'; hid-recorder's format, see hil/io/hid_recording.hpp";
  file_.write_line(line_);
}

void HidRecordingWriter::mark(std::string_view what, int64_t epoch_us, std::string_view why) {
  line_.clear();
  line_ += "# ";
  line_ += what;
  line_ += ' ';
  append_hid_time(line_, epoch_us);
  if (!why.empty()) {
    line_ += ": ";
    line_ += why;
  }
  file_.write_line(line_);
}

void HidRecordingWriter::plug(int64_t epoch_us, std::span<const uint8_t> descriptor, const HidIdentity& identity) {
  mark("plugged at", epoch_us, {});
  line_.clear();
  line_ += "R: ";
  append_unsigned(line_, descriptor.size());
  append_hex_bytes(line_, descriptor);
  file_.write_line(line_);
  // A name is one line of the file.
  auto text_line = [&](std::string_view key, const std::string& text) {
    line_.assign(key);
    for (const char c : text) line_ += c == '\n' || c == '\r' ? ' ' : c;
    file_.write_line(line_);
  };
  text_line("N: ", identity.name);
  if (!identity.phys.empty()) text_line("P: ", identity.phys);
  line_.assign("I: ");
  char text[8];
  const auto r = std::to_chars(text, text + sizeof text, identity.bus, 16);
  line_.append(text, static_cast<std::size_t>(r.ptr - text));
  for (const uint16_t id : {identity.vendor_id, identity.product_id}) {
    line_ += ' ';
    for (int shift = 12; shift >= 0; shift -= 4) line_ += kHex[(id >> shift) & 15];
  }
  file_.write_line(line_);
}

void HidRecordingWriter::report(int64_t epoch_us, std::span<const uint8_t> report) {
  if (!started_) {
    started_ = true;
    start_us_ = epoch_us;
    line_.assign("# start ");
    append_hid_time(line_, epoch_us);
    line_ += " (the wall-clock time of E: 000000.000000)";
    file_.write_line(line_);
  }
  line_.clear();
  append_hid_event(line_, epoch_us - start_us_, report);
  if (file_.write_line(line_)) reports_.fetch_add(1, std::memory_order_relaxed);
}

void HidRecordingWriter::unplug(int64_t epoch_us, std::string_view why) { mark("unplugged at", epoch_us, why); }

void HidRecordingWriter::end(int64_t epoch_us) { mark("end at", epoch_us, {}); }

HidRecordingReader::HidRecordingReader(const std::string& path) : path_(path), in_(path) {
  if (!in_) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  HidRecordingRecord scratch;
  scratch.bytes.reserve(max_hid_report_bytes);
  while (step(scratch, Mode::Check)) {
    if (scratch.kind == HidRecordingRecord::Kind::Report) ++reports_;
    if (scratch.kind == HidRecordingRecord::Kind::Plug) ++plugs_;
  }
  if (plugs_ == 0) throw std::runtime_error(path + ": no 'R:' descriptor line: not a hid-recorder file");
  epoch_ = start_seen_ || reports_ == 0;
  rewind();
}

void HidRecordingReader::rewind() {
  in_.clear();
  in_.seekg(0);
  held_ = false;
  line_ = 0;
  device_ = 0;
  plugged_ = false;
  have_plug_time_ = false;
  pending_identity_ = {};
  last_us_ = 0;
}

bool HidRecordingReader::next(HidRecordingRecord& record) { return step(record, Mode::Play); }

void HidRecordingReader::bad(Mode mode, std::string_view key, std::string_view what) const {
  if (mode == Mode::Check)
    throw std::runtime_error(path_ + ":" + std::to_string(line_) + ": " + std::string(key) + ": " + std::string(what));
}

bool HidRecordingReader::emit_plug(HidRecordingRecord& record, int block_line) {
  held_ = true;  // the line that ended the block is acted on next
  record.kind = HidRecordingRecord::Kind::Plug;
  record.time_us = epoch_ && have_plug_time_ ? plug_time_us_ : last_us_;
  record.line = block_line;
  record.identity = std::exchange(pending_identity_, {});
  have_plug_time_ = false;
  plugged_ = true;
  last_us_ = record.time_us;
  return true;
}

bool HidRecordingReader::step(HidRecordingRecord& record, Mode mode) {
  bool block = false;  // an R: block of device 0 is being read into `record`
  int block_line = 0;
  for (;;) {
    if (!held_) {
      if (!std::getline(in_, text_)) {
        if (!block) return false;
        emit_plug(record, block_line);
        held_ = false;  // nothing is left to act on
        return true;
      }
      ++line_;
    }
    held_ = false;
    const std::string_view l = trim(text_);
    if (l.empty()) continue;
    switch (l.front() == '#' ? read_mark(l, record, mode, block) : read_line(l, record, mode, block)) {
      case Action::Next: continue;
      case Action::Emit: return true;
      case Action::EndBlock: return emit_plug(record, block_line);
      case Action::StartBlock:
        block = true;
        block_line = line_;
        continue;
    }
  }
}

HidRecordingReader::Action HidRecordingReader::read_mark(std::string_view l, HidRecordingRecord& record, Mode mode,
                                                         bool in_block) {
  int64_t t = 0;
  const Mark mark = parse_mark(l, t);
  if (mark == Mark::None) return Action::Next;
  if (mark == Mark::BadTime) {
    bad(mode, "#", "the time is not SEC.USEC with six digits of microseconds");
    return Action::Next;
  }
  if (mark == Mark::Start) {
    if (!start_seen_) start_us_ = t;
    start_seen_ = true;
    return Action::Next;
  }
  if (in_block) return Action::EndBlock;
  if (device_ != 0) return Action::Next;
  if (mark == Mark::Plugged) {
    have_plug_time_ = true;
    plug_time_us_ = t;
    return Action::Next;
  }
  if (!plugged_) return Action::Next;  // nothing to unplug
  record.kind = mark == Mark::End ? HidRecordingRecord::Kind::End : HidRecordingRecord::Kind::Unplug;
  record.time_us = epoch_ ? t : last_us_;
  record.line = line_;
  last_us_ = record.time_us;
  return Action::Emit;
}

HidRecordingReader::Action HidRecordingReader::read_line(std::string_view l, HidRecordingRecord& record, Mode mode,
                                                         bool in_block) {
  if (l.size() < 2 || l[1] != ':') {
    bad(mode, l.substr(0, 1), "not a hid-recorder line (R:, N:, P:, I:, E:, D: or a # comment)");
    return Action::Next;
  }
  const char key = l.front();
  std::string_view rest = l.substr(2);
  switch (key) {
    case 'N':
    case 'P':
      if (device_ == 0) (key == 'N' ? pending_identity_.name : pending_identity_.phys) = std::string(trim(rest));
      return Action::Next;
    case 'I': return read_identity(rest, mode);
    case 'D': {
      if (in_block) return Action::EndBlock;
      int n = 0;
      if (!parse_number(trim(rest), n) || n < 0) {
        bad(mode, "D", "expected a device number");
        return Action::Next;
      }
      device_ = n;
      return Action::Next;
    }
    case 'R':
      if (in_block) return Action::EndBlock;
      if (const char* what = parse_length_and_bytes(rest, max_hid_report_bytes, record.bytes)) {
        bad(mode, "R", what);
        return Action::Next;
      }
      return device_ != 0 ? Action::Next : Action::StartBlock;
    case 'E': return in_block ? Action::EndBlock : read_event(rest, record, mode);
    default:
      bad(mode, l.substr(0, 1), "not a hid-recorder line (R:, N:, P:, I:, E:, D: or a # comment)");
      return Action::Next;
  }
}

HidRecordingReader::Action HidRecordingReader::read_identity(std::string_view rest, Mode mode) {
  uint32_t bus = 0;
  uint16_t vid = 0, pid = 0;
  const std::string_view b = next_word(rest), v = next_word(rest), p = next_word(rest);
  if (!parse_number(b, bus, 16) || !parse_number(v, vid, 16) || !parse_number(p, pid, 16) ||
      !next_word(rest).empty()) {
    bad(mode, "I", "expected '<bus> <vid> <pid>' in hex");
    return Action::Next;
  }
  if (device_ == 0) {
    pending_identity_.bus = bus;
    pending_identity_.vendor_id = vid;
    pending_identity_.product_id = pid;
  }
  return Action::Next;
}

HidRecordingReader::Action HidRecordingReader::read_event(std::string_view rest, HidRecordingRecord& record,
                                                          Mode mode) {
  int64_t t = 0;
  if (!parse_time(next_word(rest), t)) {
    bad(mode, "E", "the time is not SEC.USEC with six digits of microseconds");
    return Action::Next;
  }
  if (const char* what = parse_length_and_bytes(rest, max_hid_report_bytes, record.bytes)) {
    bad(mode, "E", what);
    return Action::Next;
  }
  if (record.bytes.empty()) {
    bad(mode, "E", "an empty report");
    return Action::Next;
  }
  if (device_ != 0) return Action::Next;
  if (!plugged_) {
    bad(mode, "E", "a report before any R: descriptor");
    return Action::Next;
  }
  record.kind = HidRecordingRecord::Kind::Report;
  record.time_us = (epoch_ ? start_us_ : 0) + t;
  record.line = line_;
  last_us_ = record.time_us;
  return Action::Emit;
}

bool looks_like_hid_recording(const std::string& path) {
  std::ifstream in(path);
  std::string text;
  while (std::getline(in, text)) {
    const std::string_view l = trim(text);
    if (l.empty() || l.front() == '#') continue;
    return l.size() >= 2 && l[1] == ':' && std::string_view("RDNPI").find(l.front()) != std::string_view::npos;
  }
  return false;
}

}  // namespace rise::hil::io
