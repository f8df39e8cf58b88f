#include "hil/app/inspect_commands.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <ostream>
#include <sstream>

#include "firmware_protocol/dbc.hpp"
#include "firmware_protocol/hid_text.hpp"
#include "hil/io/can_log.hpp"
#include "hil/io/candump_log.hpp"
#include "hil/io/modbus_capture.hpp"

namespace rise::hil {
namespace {

std::string format_value(const firmware_protocol::DecodedSignal& s) {
  if (!s.label().empty()) return "'" + std::string(s.label()) + "'";
  std::ostringstream v;
  if (s.value == std::floor(s.value) && std::fabs(s.value) < 1e15) v << static_cast<long long>(s.value);
  else v << s.value;
  return v.str();
}

}  // namespace

int dbc_decode(const std::string& dbc_file, const std::string& log_file, std::ostream& out, std::ostream& err) {
  firmware_protocol::DbcDatabase db;
  try {
    db = firmware_protocol::DbcDatabase::load(dbc_file);
  } catch (const std::exception& e) {
    err << e.what() << '\n';
    return 2;
  }
  std::optional<io::CanLogReader> reader;
  try {
    reader.emplace(log_file);
  } catch (const std::exception& e) {
    err << e.what() << '\n';
    return 2;
  }
  int64_t frames = 0, decoded = 0, unknown = 0;
  std::map<uint32_t, int64_t> unknown_ids;
  io::CanLogRecord record;
  std::string line;
  while (reader->next(record)) {
    ++frames;
    const auto& f = record.frame;
    const firmware_protocol::DbcMessage* message = f.error || f.remote ? nullptr : db.find(f.id, f.extended);
    line.clear();
    io::append_candump_line(line, f, record.channel.empty() ? "can0" : record.channel);
    out << line;
    if (!message) {
      ++unknown;
      ++unknown_ids[f.id];
      out << '\n';
      continue;
    }
    ++decoded;
    out << " :: " << message->name << '(';
    bool first = true;
    for (const auto& s : db.decode(*message, std::span<const uint8_t>(f.data.data(), f.len))) {
      out << (first ? "" : ", ") << s.signal->name << ": " << format_value(s);
      if (!s.signal->unit.empty() && s.label().empty()) out << ' ' << s.signal->unit;
      first = false;
    }
    out << ")\n";
  }
  for (const int bad : reader->malformed_lines())
    err << log_file << ':' << bad << ": not a frame, skipped\n";
  const size_t bad_lines = reader->malformed_count();
  out << "# " << frames << " frames: " << decoded << " with a message in " << dbc_file << " ("
      << (frames ? 100 * decoded / frames : 0) << " %), " << unknown << " without";
  if (!unknown_ids.empty()) {
    out << " (ids";
    for (const auto& [id, n] : unknown_ids) out << ' ' << std::hex << std::uppercase << id << std::dec << 'x' << n;
    out << ')';
  }
  if (bad_lines) out << ", " << bad_lines << " unreadable lines";
  out << '\n';
  return bad_lines && frames == 0 ? 2 : 0;
}

namespace {

std::string modbus_row(const io::ModbusCaptureTransaction& t, int64_t start_us) {
  const auto opt = [](const std::optional<uint16_t>& v) { return v ? std::to_string(*v) : std::string("-"); };
  std::string result = "no response", ms = "-";
  if (t.response_us) {
    result = t.exception ? "exception " + std::to_string(*t.exception) + " (" + io::modbus_exception_name(*t.exception) + ")"
                         : "ok";
    char text[32];
    std::snprintf(text, sizeof text, "%.3f", static_cast<double>(*t.response_us - t.request_us) / 1000.0);
    ms = text;
  }
  char row[512];
  std::snprintf(row, sizeof row, "%12.6f  %-24s %-24s %5u %4u %3u %-30s %7s %6s  %-34s %9s",
                static_cast<double>(t.request_us - start_us) / 1e6, t.client.c_str(), t.server.c_str(),
                t.transaction_id, t.unit, t.function, io::modbus_function_name(t.function).c_str(),
                opt(t.address).c_str(), opt(t.count).c_str(), result.c_str(), ms.c_str());
  return row;
}

}  // namespace

int modbus_decode(const std::string& capture_file, std::ostream& out, std::ostream& err) {
  io::ModbusCapture capture;
  try {
    capture = io::read_modbus_capture(capture_file);
  } catch (const std::exception& e) {
    err << e.what() << '\n';
    return 2;
  }
  const int64_t start_us = capture.transactions.empty() ? 0 : capture.transactions.front().request_us;
  char header[512];
  std::snprintf(header, sizeof header, "# %10s  %-24s %-24s %5s %4s %3s %-30s %7s %6s  %-34s %9s", "time_s", "client",
                "server", "tid", "unit", "fc", "function", "address", "count", "result", "ms");
  out << header << '\n';
  uint64_t unanswered = 0;
  for (const auto& t : capture.transactions) {
    out << modbus_row(t, start_us) << '\n';
    unanswered += !t.response_us;
  }
  const io::ModbusCaptureStats& s = capture.stats;
  out << "# " << capture.transactions.size() << " transactions: " << capture.transactions.size() - unanswered
      << " answered (" << s.exceptions << " exceptions), " << unanswered << " without response; " << s.packets
      << " packets, " << s.modbus_segments << " Modbus segments, " << s.retransmissions << " retransmissions, "
      << s.unmatched_responses << " unmatched responses, " << s.malformed << " malformed\n";
  if (s.modbus_segments == 0) {
    err << capture_file << ": no Modbus/TCP (port 502) traffic\n";
    return 2;
  }
  return 0;
}

int hid_describe(const std::string& file, std::ostream& out, std::ostream& err) {
  try {
    out << firmware_protocol::describe_hid_descriptor(firmware_protocol::load_hid_descriptor_file(file));
  } catch (const std::exception& e) {
    err << e.what() << '\n';
    return 2;
  }
  return 0;
}

}  // namespace rise::hil
