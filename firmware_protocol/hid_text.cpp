#include "firmware_protocol/hid_text.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <stdexcept>

#include "firmware_protocol/hid_report.hpp"

namespace rise::firmware_protocol {

namespace {

[[noreturn]] void fail(const std::string& file, uint32_t line, std::string_view key, const std::string& message) {
  throw std::runtime_error(file + ":" + std::to_string(line) + ": " + std::string(key) + ": " + message);
}

bool is_hex_digit(char c) {
  return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F');
}

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return c - 'A' + 10;
}

// "05", "5", "0x05", "0X5": one byte; anything else is not a byte.
bool parse_hex_byte(std::string_view token, uint8_t& out) {
  if (token.size() > 2 && token[0] == '0' && (token[1] == 'x' || token[1] == 'X')) token.remove_prefix(2);
  if (token.empty() || token.size() > 2) return false;
  int v = 0;
  for (const char c : token) {
    if (!is_hex_digit(c)) return false;
    v = v * 16 + hex_value(c);
  }
  out = static_cast<uint8_t>(v);
  return true;
}

bool is_separator(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == ',' || c == '{' || c == '}' || c == ';';
}

// Hex bytes separated by blanks or commas, with C and shell comments.
void read_hex_tokens(std::string_view text, uint32_t first_line, const std::string& file,
                     HidDescriptorSource& out) {
  uint32_t line = first_line;
  bool line_start = true;
  std::size_t i = 0;
  while (i < text.size()) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
      line_start = true;
      ++i;
      continue;
    }
    if (is_separator(c)) {
      ++i;
      continue;
    }
    if (c == '/' && i + 1 < text.size() && text[i + 1] == '/') {
      while (i < text.size() && text[i] != '\n') ++i;
      continue;
    }
    if (c == '/' && i + 1 < text.size() && text[i + 1] == '*') {
      i += 2;
      while (i < text.size() && !(text[i] == '*' && i + 1 < text.size() && text[i + 1] == '/')) {
        if (text[i] == '\n') ++line;
        ++i;
      }
      if (i >= text.size()) fail(file, line, "descriptor", "unterminated /* comment");
      i += 2;
      continue;
    }
    if (c == '#' && line_start) {
      while (i < text.size() && text[i] != '\n') ++i;
      continue;
    }
    line_start = false;
    const std::size_t begin = i++;
    while (i < text.size() && text[i] != '\n' && !is_separator(text[i]) && text[i] != '/') ++i;
    const std::string_view token = text.substr(begin, i - begin);
    uint8_t byte = 0;
    if (!parse_hex_byte(token, byte)) fail(file, line, "descriptor", "'" + std::string(token) + "' is not a hex byte");
    out.bytes.push_back(byte);
    out.lines.push_back(line);
  }
}

std::vector<std::string_view> split_lines(std::string_view text) {
  std::vector<std::string_view> lines;
  std::size_t begin = 0;
  while (begin <= text.size()) {
    const std::size_t end = text.find('\n', begin);
    std::string_view l = text.substr(begin, end == std::string_view::npos ? std::string_view::npos : end - begin);
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    lines.push_back(l);
    if (end == std::string_view::npos) break;
    begin = end + 1;
  }
  return lines;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> words(std::string_view s) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    const std::size_t begin = i;
    while (i < s.size() && s[i] != ' ' && s[i] != '\t') ++i;
    if (i > begin) out.push_back(s.substr(begin, i - begin));
  }
  return out;
}

bool parse_unsigned(std::string_view s, int base, uint32_t& out) {
  if (s.empty() || s.size() > 10) return false;
  std::string copy(s);
  char* end = nullptr;
  errno = 0;
  const unsigned long v = std::strtoul(copy.c_str(), &end, base);
  if (errno != 0 || end != copy.c_str() + copy.size() || v > 0xFFFFFFFFul) return false;
  out = static_cast<uint32_t>(v);
  return true;
}

// hid-recorder (hid-tools): "R: 148 05 01 ...", "N: name", "I: 3 054c 0268".
HidDescriptorSource read_recorder(std::string_view text, const std::string& file) {
  HidDescriptorSource out;
  const std::vector<std::string_view> lines = split_lines(text);
  bool have_r = false;
  for (std::size_t n = 0; n < lines.size(); ++n) {
    const auto line_no = static_cast<uint32_t>(n + 1);
    const std::string_view l = lines[n];
    if (l.starts_with("R:") && !have_r) {
      const std::vector<std::string_view> w = words(l.substr(2));
      uint32_t length = 0;
      if (w.empty() || !parse_unsigned(w[0], 10, length)) fail(file, line_no, "R", "missing descriptor length");
      if (w.size() - 1 != length) {
        fail(file, line_no, "R",
             "length " + std::to_string(length) + " but " + std::to_string(w.size() - 1) + " bytes");
      }
      for (std::size_t i = 1; i < w.size(); ++i) {
        uint8_t byte = 0;
        if (!parse_hex_byte(w[i], byte)) fail(file, line_no, "R", "'" + std::string(w[i]) + "' is not a hex byte");
        out.bytes.push_back(byte);
        out.lines.push_back(line_no);
      }
      have_r = true;
    } else if (l.starts_with("N:") && out.name.empty()) {
      out.name = std::string(trim(l.substr(2)));
    } else if (l.starts_with("I:")) {
      const std::vector<std::string_view> w = words(l.substr(2));
      uint32_t bus = 0, vid = 0, pid = 0;
      if (w.size() != 3 || !parse_unsigned(w[0], 16, bus) || !parse_unsigned(w[1], 16, vid) ||
          !parse_unsigned(w[2], 16, pid) || vid > 0xFFFF || pid > 0xFFFF) {
        fail(file, line_no, "I", "expected '<bus> <vid> <pid>' in hex");
      }
      out.bus = bus;
      out.vendor_id = static_cast<uint16_t>(vid);
      out.product_id = static_cast<uint16_t>(pid);
    }
  }
  if (!have_r) fail(file, 0, "R", "no 'R:' descriptor line");
  return out;
}

// A line that holds only hex bytes (the body of an xxd -g1 dump).
bool is_hex_dump_line(std::string_view l) {
  const std::vector<std::string_view> w = words(trim(l));
  if (w.empty()) return false;
  uint8_t b = 0;
  for (const std::string_view t : w) {
    if (t.size() != 2 || !parse_hex_byte(t, b)) return false;
  }
  return true;
}

// xpadneo docs: the first ``` block whose lines are hex bytes (or # comments).
HidDescriptorSource read_markdown(std::string_view text, const std::string& file) {
  const std::vector<std::string_view> lines = split_lines(text);
  std::size_t n = 0;
  while (n < lines.size()) {
    if (!trim(lines[n]).starts_with("```")) {
      ++n;
      continue;
    }
    const std::size_t begin = n + 1;
    std::size_t end = begin;
    while (end < lines.size() && !trim(lines[end]).starts_with("```")) ++end;
    bool hex_only = true;
    bool any = false;
    for (std::size_t k = begin; k < end; ++k) {
      const std::string_view l = trim(lines[k]);
      if (l.empty() || l.starts_with("#")) continue;
      if (!is_hex_dump_line(l)) {
        hex_only = false;
        break;
      }
      any = true;
    }
    if (hex_only && any) {
      HidDescriptorSource out;
      for (std::size_t k = begin; k < end; ++k) {
        read_hex_tokens(lines[k], static_cast<uint32_t>(k + 1), file, out);
      }
      return out;
    }
    n = end + 1;
  }
  fail(file, 0, "descriptor", "no fenced block of hex bytes");
}

uint32_t line_of(std::string_view text, std::size_t pos) {
  uint32_t line = 1;
  for (std::size_t i = 0; i < pos && i < text.size(); ++i) line += text[i] == '\n' ? 1u : 0u;
  return line;
}

// The value text after `"key":` up to the next ',' / '}' / newline.
std::string_view json_scalar(std::string_view text, std::string_view key, std::size_t& pos) {
  const std::string quoted = "\"" + std::string(key) + "\"";
  pos = text.find(quoted);
  if (pos == std::string_view::npos) return {};
  std::size_t i = text.find(':', pos + quoted.size());
  if (i == std::string_view::npos) return {};
  ++i;
  while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
  if (i < text.size() && text[i] == '"') {
    const std::size_t close = text.find('"', i + 1);
    if (close == std::string_view::npos) return {};
    return text.substr(i + 1, close - i - 1);
  }
  std::size_t end = i;
  while (end < text.size() && text[end] != ',' && text[end] != '}' && text[end] != '\n' && text[end] != '\r') ++end;
  return trim(text.substr(i, end - i));
}

// Android CTS hid "register" command (cts/tests/tests/hardware/res/raw).
HidDescriptorSource read_cts_json(std::string_view text, const std::string& file) {
  HidDescriptorSource out;
  std::size_t pos = 0;
  const std::size_t key = text.find("\"descriptor\"");
  if (key == std::string_view::npos) fail(file, 0, "descriptor", "no \"descriptor\" key");
  const std::size_t open = text.find('[', key);
  const std::size_t close = open == std::string_view::npos ? open : text.find(']', open);
  if (open == std::string_view::npos || close == std::string_view::npos) {
    fail(file, line_of(text, key), "descriptor", "expected a [ ... ] byte list");
  }
  read_hex_tokens(text.substr(open + 1, close - open - 1), line_of(text, open), file, out);
  out.name = std::string(json_scalar(text, "name", pos));
  uint32_t v = 0;
  const std::string_view vid = json_scalar(text, "vid", pos);
  if (!vid.empty()) {
    if (!parse_unsigned(vid, 0, v) || v > 0xFFFF) fail(file, line_of(text, pos), "vid", "not a 16-bit number");
    out.vendor_id = static_cast<uint16_t>(v);
  }
  const std::string_view pid = json_scalar(text, "pid", pos);
  if (!pid.empty()) {
    if (!parse_unsigned(pid, 0, v) || v > 0xFFFF) fail(file, line_of(text, pos), "pid", "not a 16-bit number");
    out.product_id = static_cast<uint16_t>(v);
  }
  return out;
}

std::string_view page_name(uint16_t page) {
  switch (page) {
    case 0x01: return "Generic Desktop";
    case 0x02: return "Simulation";
    case 0x06: return "Generic Device";
    case 0x07: return "Keyboard";
    case 0x08: return "LED";
    case 0x09: return "Button";
    case 0x0C: return "Consumer";
    case 0x0F: return "PID";
    default: return page >= 0xFF00 ? "Vendor" : "";
  }
}

std::string hex(uint32_t v, int digits) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%0*x", digits, static_cast<unsigned>(v));
  return buf;
}

std::string usage_text(HidUsage u) {
  std::string s = hex(hid_usage_page(u), 2) + ":" + hex(hid_usage_id(u), 2);
  return s;
}

std::string_view collection_name(uint8_t type) {
  switch (type) {
    case 0x00: return "Physical";
    case 0x01: return "Application";
    case 0x02: return "Logical";
    case 0x03: return "Report";
    case 0x04: return "NamedArray";
    case 0x05: return "UsageSwitch";
    case 0x06: return "UsageModifier";
    default: return "Vendor";
  }
}

std::string flags_text(uint32_t flags) {
  std::string s = (flags & hid_flags::constant) ? "Cnst" : "Data";
  s += (flags & hid_flags::variable) ? ",Var" : ",Arr";
  s += (flags & hid_flags::relative) ? ",Rel" : ",Abs";
  if (flags & hid_flags::wrap) s += ",Wrap";
  if (flags & hid_flags::non_linear) s += ",NonLin";
  if (flags & hid_flags::no_preferred) s += ",NoPref";
  if (flags & hid_flags::null_state) s += ",Null";
  if (flags & hid_flags::buffered_bytes) s += ",Buf";
  return s;
}

}  // namespace

HidTextFormat detect_hid_format(std::string_view content, std::string_view file_name) {
  const std::size_t probe = std::min<std::size_t>(content.size(), 256);
  for (std::size_t i = 0; i < probe; ++i) {
    const auto c = static_cast<unsigned char>(content[i]);
    if ((c < 0x20 && c != '\t' && c != '\n' && c != '\r') || c == 0x7F) return HidTextFormat::Binary;
  }
  if (file_name.ends_with(".md") || content.find("```") != std::string_view::npos) return HidTextFormat::Markdown;
  if (content.find("\"descriptor\"") != std::string_view::npos) return HidTextFormat::CtsJson;
  if (content.starts_with("R:") || content.find("\nR:") != std::string_view::npos) {
    return HidTextFormat::HidRecorder;
  }
  return HidTextFormat::HexText;
}

HidDescriptorSource read_hid_descriptor(std::string_view content, HidTextFormat format,
                                        const std::string& file_name) {
  HidDescriptorSource out;
  switch (format) {
    case HidTextFormat::Binary:
      out.bytes.assign(content.begin(), content.end());
      out.lines.assign(content.size(), 0);
      break;
    case HidTextFormat::HexText: read_hex_tokens(content, 1, file_name, out); break;
    case HidTextFormat::HidRecorder: out = read_recorder(content, file_name); break;
    case HidTextFormat::Markdown: out = read_markdown(content, file_name); break;
    case HidTextFormat::CtsJson: out = read_cts_json(content, file_name); break;
  }
  if (out.bytes.empty()) fail(file_name, 0, "descriptor", "no descriptor bytes");
  return out;
}

HidDescriptorSource read_hid_descriptor_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  const std::string content((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return read_hid_descriptor(content, detect_hid_format(content, path), path);
}

HidDescriptor load_hid_descriptor_file(const std::string& path) {
  const HidDescriptorSource source = read_hid_descriptor_file(path);
  HidParseResult result = parse_hid_descriptor(source.bytes);
  if (!result) {
    const uint32_t line = result.error_offset < source.lines.size() ? source.lines[result.error_offset]
                          : source.lines.empty()                    ? 0
                                                                    : source.lines.back();
    fail(path, line, "descriptor",
         "byte " + std::to_string(result.error_offset) + ": " + std::string(to_string(result.error)));
  }
  return std::move(result.descriptor);
}

std::string describe_hid_descriptor(const HidDescriptor& descriptor) {
  std::ostringstream out;
  out << "HID report descriptor: " << descriptor.fields.size() << " fields, " << descriptor.reports.size()
      << " reports" << (descriptor.uses_report_ids ? " (report ids used)" : " (no report ids)") << "\n";
  std::map<std::size_t, std::vector<std::string>> names;
  for (const HidReportKind kind : {HidReportKind::Input, HidReportKind::Output, HidReportKind::Feature}) {
    for (const HidSignal& s : hid_signals(descriptor, kind)) names[s.field_index].push_back(s.name);
  }
  std::map<std::pair<HidReportKind, uint8_t>, std::vector<std::size_t>> fields_of;
  for (std::size_t i = 0; i < descriptor.fields.size(); ++i) {
    fields_of[{descriptor.fields[i].kind, descriptor.fields[i].report_id}].push_back(i);
  }
  for (const HidReportLayout& r : descriptor.reports) {
    out << "\n" << to_string(r.kind) << " report " << unsigned{r.report_id} << ": "
        << descriptor.report_length(r.report_id, r.kind) << " bytes on the wire, " << r.size_bits << " data bits\n";
    for (const std::size_t i : fields_of[{r.kind, r.report_id}]) {
      const HidField& f = descriptor.fields[i];
      out << "  bit " << f.bit_offset << " size " << f.bit_size << " count " << f.count << "  page "
          << hex(f.usage_page, 2);
      const std::string_view pn = page_name(f.usage_page);
      if (!pn.empty()) out << " (" << pn << ")";
      out << "  usages";
      if (f.usages.empty()) out << " none";
      for (const HidUsageRange& u : f.usages) {
        out << " " << usage_text(u.first);
        if (u.last != u.first) out << ".." << usage_text(u.last);
        else out << " (" << hid_usage_name(u.first) << ")";
      }
      out << "\n    logical " << f.logical_min << ".." << f.logical_max << "  physical " << f.physical_min << ".."
          << f.physical_max;
      if (f.unit != 0) out << "  unit " << hex(f.unit, 4) << " exp " << f.unit_exponent;
      out << "  " << flags_text(f.flags);
      if (f.is_signed()) out << " signed";
      out << "\n    collections";
      if (f.collection_path.empty()) out << " none";
      for (const HidCollection& c : f.collection_path) {
        out << " " << collection_name(c.type) << "(" << usage_text(c.usage) << ")";
      }
      const auto it = names.find(i);
      if (f.is_constant()) {
        out << "\n    -> padding";
      } else if (it != names.end()) {
        out << "\n    ->";
        for (const std::string& n : it->second) out << " " << n;
      }
      out << "\n";
    }
  }
  return out.str();
}

}  // namespace rise::firmware_protocol
