#include "hil/app/inspect_commands.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <ostream>
#include <sstream>

#include "firmware_protocol/dbc.hpp"
#include "firmware_protocol/hid_text.hpp"
#include "hil/io/candump_log.hpp"

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
  std::ifstream in(log_file);
  if (!in) {
    err << log_file << ": cannot open: " << std::strerror(errno) << '\n';
    return 2;
  }
  int64_t frames = 0, decoded = 0, unknown = 0, bad_lines = 0;
  std::map<uint32_t, int64_t> unknown_ids;
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    const auto parsed = io::parse_candump_line(line);
    if (parsed.error == io::CandumpError::Empty) continue;
    if (!parsed.ok()) {
      err << log_file << ':' << line_no << ": " << io::to_string(parsed.error) << ", line skipped\n";
      ++bad_lines;
      continue;
    }
    ++frames;
    const auto& f = parsed.record.frame;
    const firmware_protocol::DbcMessage* message = f.error || f.remote ? nullptr : db.find(f.id, f.extended);
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
