#include "hil/io/modbus_trace.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "hil/io/candump_log.hpp"

namespace rise::hil::io {
namespace {

const char* result_text(ModbusStatus status) {
  switch (status) {
    case ModbusStatus::Ok: return "ok";
    case ModbusStatus::Timeout: return "timeout";
    case ModbusStatus::Exception: return "exception";
    case ModbusStatus::CrcError: return "crc";
    case ModbusStatus::Disconnected: return "disconnected";
    case ModbusStatus::Error: return "error";
  }
  return "error";
}

void append_number(std::string& out, int64_t value) {
  char text[24];
  const auto r = std::to_chars(text, text + sizeof text, value);
  out.append(text, static_cast<std::size_t>(r.ptr - text));
}

void append_head(std::string& out, int64_t time_us, std::string_view source, int unit, ModbusFunction function,
                 uint16_t address, uint16_t count, int64_t rtt_us, const ModbusResult& result, bool closed) {
  append_log_time(out, time_us);
  out += ' ';
  out += source;
  out += " unit=";
  append_number(out, unit);
  out += " fc=";
  const auto fc = static_cast<unsigned>(function);
  out += static_cast<char>('0' + fc / 10);
  out += static_cast<char>('0' + fc % 10);
  out += " addr=";
  append_number(out, address);
  out += " count=";
  append_number(out, count);
  out += " rtt_us=";
  append_number(out, rtt_us);
  out += ' ';
  out += result_text(result.status);
  if (result.status == ModbusStatus::Exception) {
    static const char* digits = "0123456789ABCDEF";
    out += '=';
    out += digits[result.exception_code >> 4];
    out += digits[result.exception_code & 0xF];
  }
  if (closed) out += " closed";
}

// Values go with a read only when it succeeded; a write always says what it wrote.
bool has_values(ModbusFunction function, const ModbusResult& result) {
  const bool write = function == ModbusFunction::WriteMultipleCoils || function == ModbusFunction::WriteMultipleRegisters;
  return write || result.ok();
}

// The next blank-separated word of `rest` (empty at the end); `rest` moves past it.
std::string_view next_word(std::string_view& rest) {
  const auto begin = rest.find_first_not_of(" \t");
  if (begin == std::string_view::npos) return rest = {}, std::string_view();
  rest.remove_prefix(begin);
  const std::size_t end = std::min(rest.find_first_of(" \t"), rest.size());
  const std::string_view word = rest.substr(0, end);
  rest.remove_prefix(end);
  return word;
}

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> words;
  for (std::string_view w = next_word(line); !w.empty(); w = next_word(line)) words.push_back(w);
  return words;
}

template <typename T>
bool parse_field(std::string_view token, std::string_view key, T& value, int base = 10) {
  if (token.size() <= key.size() || token.substr(0, key.size()) != key) return false;
  const std::string_view text = token.substr(key.size());
  const auto r = std::from_chars(text.data(), text.data() + text.size(), value, base);
  return r.ec == std::errc() && r.ptr == text.data() + text.size();
}

}  // namespace

bool is_bit_function(ModbusFunction function) {
  return function == ModbusFunction::ReadCoils || function == ModbusFunction::ReadDiscreteInputs ||
         function == ModbusFunction::WriteMultipleCoils;
}

void append_modbus_transaction(std::string& out, int64_t time_us, std::string_view source, int unit,
                               ModbusFunction function, uint16_t address, uint16_t count, int64_t rtt_us,
                               const ModbusResult& result, bool closed, std::span<const uint16_t> values) {
  append_head(out, time_us, source, unit, function, address, count, rtt_us, result, closed);
  if (!has_values(function, result)) return;
  static const char* digits = "0123456789ABCDEF";
  for (const uint16_t v : values) {
    out += ' ';
    for (int shift = 12; shift >= 0; shift -= 4) out += digits[(v >> shift) & 0xF];
  }
}

void append_modbus_transaction(std::string& out, int64_t time_us, std::string_view source, int unit,
                               ModbusFunction function, uint16_t address, uint16_t count, int64_t rtt_us,
                               const ModbusResult& result, bool closed, std::span<const uint8_t> bits) {
  append_head(out, time_us, source, unit, function, address, count, rtt_us, result, closed);
  if (!has_values(function, result) || bits.empty()) return;
  out += ' ';
  for (const uint8_t b : bits) out += b != 0 ? '1' : '0';
}

void append_modbus_event(std::string& out, int64_t time_us, std::string_view source, ModbusTraceRecord::Kind kind,
                         bool open) {
  append_log_time(out, time_us);
  out += ' ';
  out += source;
  switch (kind) {
    case ModbusTraceRecord::Kind::Link: out += open ? " link open" : " link closed"; break;
    case ModbusTraceRecord::Kind::Reopen: out += open ? " reopen ok" : " reopen failed"; break;
    case ModbusTraceRecord::Kind::Close: out += " close"; break;
    case ModbusTraceRecord::Kind::Transaction: break;
  }
}

std::string format_modbus_trace_line(const ModbusTraceRecord& r) {
  std::string out;
  if (r.kind != ModbusTraceRecord::Kind::Transaction) {
    append_modbus_event(out, r.time_us, r.source, r.kind, r.open);
  } else if (is_bit_function(r.function)) {
    std::vector<uint8_t> bits(r.values.begin(), r.values.end());
    append_modbus_transaction(out, r.time_us, r.source, r.unit, r.function, r.address, r.count, r.rtt_us, r.result,
                              r.closed, std::span<const uint8_t>(bits));
  } else {
    append_modbus_transaction(out, r.time_us, r.source, r.unit, r.function, r.address, r.count, r.rtt_us, r.result,
                              r.closed, std::span<const uint16_t>(r.values));
  }
  return out;
}

ModbusTraceParse parse_modbus_trace_line(std::string_view line) {
  ModbusTraceParse p;
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r' || line.back() == ' ')) line.remove_suffix(1);
  while (!line.empty() && line.front() == ' ') line.remove_prefix(1);
  if (line.empty() || line.front() == '#') {
    p.skip = true;
    return p;
  }
  auto fail = [&](std::string what) {
    p.error = std::move(what);
    return p;
  };
  std::string_view rest;
  const std::optional<int64_t> time_us = parse_log_time(line, &rest);
  if (!time_us) return fail("no (seconds.micros) time");
  ModbusTraceRecord& r = p.record;
  r.time_us = *time_us;
  const std::vector<std::string_view> tok = split(rest);
  if (tok.size() < 2) return fail("no source and event after the time");
  r.source = std::string(tok[0]);
  using Kind = ModbusTraceRecord::Kind;
  if (tok[1] == "link" || tok[1] == "reopen" || tok[1] == "close") {
    r.kind = tok[1] == "link" ? Kind::Link : tok[1] == "reopen" ? Kind::Reopen : Kind::Close;
    if (r.kind == Kind::Close) {
      if (tok.size() != 2) return fail("'close' takes nothing after it");
    } else {
      const std::string_view yes = r.kind == Kind::Link ? "open" : "ok";
      const std::string_view no = r.kind == Kind::Link ? "closed" : "failed";
      if (tok.size() != 3 || (tok[2] != yes && tok[2] != no))
        return fail("expected '" + std::string(tok[1]) + " " + std::string(yes) + "' or '" + std::string(tok[1]) +
                    " " + std::string(no) + "'");
      r.open = tok[2] == yes;
    }
    p.ok = true;
    return p;
  }
  if (tok.size() < 7) return fail("a transaction needs unit= fc= addr= count= rtt_us= and a result");
  unsigned fc = 0;
  if (!parse_field(tok[1], "unit=", r.unit)) return fail("bad unit= field '" + std::string(tok[1]) + "'");
  if (!parse_field(tok[2], "fc=", fc) || !((fc >= 1 && fc <= 4) || fc == 15 || fc == 16))
    return fail("bad fc= field '" + std::string(tok[2]) + "' (01, 02, 03, 04, 15 or 16)");
  r.function = static_cast<ModbusFunction>(fc);
  if (!parse_field(tok[3], "addr=", r.address)) return fail("bad addr= field '" + std::string(tok[3]) + "'");
  if (!parse_field(tok[4], "count=", r.count)) return fail("bad count= field '" + std::string(tok[4]) + "'");
  if (!parse_field(tok[5], "rtt_us=", r.rtt_us) || r.rtt_us < 0)
    return fail("bad rtt_us= field '" + std::string(tok[5]) + "'");
  const std::string_view result = tok[6];
  if (result == "ok") r.result.status = ModbusStatus::Ok;
  else if (result == "timeout") r.result.status = ModbusStatus::Timeout;
  else if (result == "crc") r.result.status = ModbusStatus::CrcError;
  else if (result == "disconnected") r.result.status = ModbusStatus::Disconnected;
  else if (result == "error") r.result.status = ModbusStatus::Error;
  else if (parse_field(result, "exception=", r.result.exception_code, 16)) r.result.status = ModbusStatus::Exception;
  else return fail("bad result '" + std::string(result) + "'");
  std::size_t i = 7;
  if (i < tok.size() && tok[i] == "closed") {
    r.closed = true;
    ++i;
  }
  const bool values = has_values(r.function, r.result);
  if (is_bit_function(r.function)) {
    if (values) {
      if (i + 1 != tok.size() && !(i == tok.size() && r.count == 0))
        return fail("expected one string of count=" + std::to_string(r.count) + " bits");
      const std::string_view bits = i < tok.size() ? tok[i] : std::string_view();
      if (bits.size() != r.count)
        return fail("count=" + std::to_string(r.count) + " but " + std::to_string(bits.size()) + " bits");
      for (const char c : bits) {
        if (c != '0' && c != '1') return fail("bit '" + std::string(1, c) + "' is not 0 or 1");
        r.values.push_back(c == '1' ? 1 : 0);
      }
      i = tok.size();
    }
  } else if (values) {
    for (; i < tok.size(); ++i) {
      uint16_t v = 0;
      const auto res = std::from_chars(tok[i].data(), tok[i].data() + tok[i].size(), v, 16);
      if (tok[i].size() != 4 || res.ec != std::errc() || res.ptr != tok[i].data() + tok[i].size())
        return fail("register '" + std::string(tok[i]) + "' is not four hex digits");
      r.values.push_back(v);
    }
    if (r.values.size() != r.count)
      return fail("count=" + std::to_string(r.count) + " but " + std::to_string(r.values.size()) + " registers");
  }
  if (i != tok.size()) return fail("unexpected '" + std::string(tok[i]) + "' after the result");
  p.ok = true;
  return p;
}

ModbusTraceReader::ModbusTraceReader(const std::string& path) : path_(path), in_(path) {
  if (!in_) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
}

bool ModbusTraceReader::next(ModbusTraceRecord& record) {
  while (std::getline(in_, text_)) {
    ++line_;
    ModbusTraceParse p = parse_modbus_trace_line(text_);
    if (p.skip) continue;
    if (!p.ok) throw std::runtime_error(path_ + ":" + std::to_string(line_) + ": " + p.error);
    record = std::move(p.record);
    record.line = line_;
    return true;
  }
  return false;
}

bool looks_like_modbus_trace(const std::string& path) {
  std::ifstream in(path);
  std::string text;
  while (std::getline(in, text)) {
    if (text.rfind("# rise-hild modbus trace", 0) == 0) return true;
    const ModbusTraceParse p = parse_modbus_trace_line(text);
    if (!p.skip) return p.ok;
  }
  return false;
}

}  // namespace rise::hil::io
