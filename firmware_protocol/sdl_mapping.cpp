#include "firmware_protocol/sdl_mapping.hpp"

#include <algorithm>
#include <charconv>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace rise::firmware_protocol {
namespace {

// SDL_gamecontroller.c's map_StringForControllerAxis / ...Button (SDL 2.26).
constexpr std::array<std::string_view, 6> kAxes = {"leftx", "lefty", "rightx", "righty", "lefttrigger", "righttrigger"};
// misc2..misc6 are SDL3's (the database carries them for it).
constexpr std::array<std::string_view, 26> kButtons = {
    "a",      "b",      "x",      "y",      "back",    "guide",   "start",   "leftstick", "rightstick",
    "leftshoulder", "rightshoulder", "dpup", "dpdown", "dpleft", "dpright", "misc1", "misc2", "misc3",
    "misc4",  "misc5",  "misc6",  "paddle1", "paddle2", "paddle3", "paddle4", "touchpad"};

void put_le16(SdlGuid& guid, std::size_t word, uint16_t value) {
  guid[2 * word] = static_cast<uint8_t>(value & 0xff);
  guid[2 * word + 1] = static_cast<uint8_t>(value >> 8);
}

std::optional<int> parse_int(std::string_view text) {
  int value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size() || value < 0) return std::nullopt;
  return value;
}

// bN, aN, +aN, -aN, aN~, hN.M
std::optional<SdlInput> parse_input(std::string_view text) {
  SdlInput in;
  if (!text.empty() && (text.front() == '+' || text.front() == '-')) {
    in.half = text.front() == '+' ? 1 : -1;
    text.remove_prefix(1);
  }
  if (!text.empty() && text.back() == '~') {
    in.invert = true;
    text.remove_suffix(1);
  }
  if (text.size() < 2) return std::nullopt;
  const char kind = text.front();
  text.remove_prefix(1);
  if (kind == 'h') {
    const auto dot = text.find('.');
    if (dot == std::string_view::npos || in.half != 0 || in.invert) return std::nullopt;
    const auto hat = parse_int(text.substr(0, dot)), mask = parse_int(text.substr(dot + 1));
    if (!hat || !mask || *mask < 1 || *mask > 15) return std::nullopt;
    in.kind = SdlInput::Kind::Hat;
    in.index = *hat;
    in.hat_mask = *mask;
    return in;
  }
  const auto index = parse_int(text);
  if (!index || (kind != 'a' && kind != 'b') || (kind == 'b' && (in.half != 0 || in.invert))) return std::nullopt;
  in.kind = kind == 'a' ? SdlInput::Kind::Axis : SdlInput::Kind::Button;
  in.index = *index;
  return in;
}

// One TARGET:INPUT element (platform: handled by the caller).
bool parse_element(std::string_view key, std::string_view value, SdlMapping& out, std::string& error) {
  SdlBinding b;
  if (!key.empty() && (key.front() == '+' || key.front() == '-')) {
    b.target_half = key.front() == '+' ? 1 : -1;
    key.remove_prefix(1);
  }
  const bool axis = is_sdl_axis(key);
  if (!axis && !is_sdl_button(key)) {
    error = "unknown target '" + std::string(key) + "'";
    return false;
  }
  if (b.target_half != 0 && !axis) {
    error = "'" + std::string(key) + "' is a button: no +/- half";
    return false;
  }
  const auto input = parse_input(value);
  if (!input) {
    error = "'" + std::string(key) + ":" + std::string(value) + "': expected bN, aN, +aN, -aN, aN~ or hN.M";
    return false;
  }
  b.target = key;
  b.input = *input;
  out.bindings.push_back(std::move(b));
  return true;
}

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

bool same_device(const SdlGuid& entry, const SdlGuid& device, bool match_version) {
  for (std::size_t i = 0; i < entry.size(); ++i) {
    if (i == 2 || i == 3) continue;  // the name's CRC: the database writes 0
    if (!match_version && (i == 12 || i == 13)) continue;
    if (i >= 14) continue;  // driver signature and data
    if (entry[i] != device[i]) return false;
  }
  return true;
}

}  // namespace

SdlGuid sdl_linux_guid(uint16_t bus, uint16_t vendor, uint16_t product, uint16_t version) {
  SdlGuid guid{};
  put_le16(guid, 0, bus);
  put_le16(guid, 2, vendor);
  put_le16(guid, 4, product);
  put_le16(guid, 6, version);
  return guid;
}

std::string to_string(const SdlGuid& guid) {
  static constexpr char digits[] = "0123456789abcdef";
  std::string out;
  for (const uint8_t b : guid) {
    out.push_back(digits[b >> 4]);
    out.push_back(digits[b & 0xf]);
  }
  return out;
}

std::optional<SdlGuid> parse_sdl_guid(std::string_view text) {
  if (text.size() != 32) return std::nullopt;
  SdlGuid guid{};
  for (std::size_t i = 0; i < guid.size(); ++i) {
    const int hi = hex_digit(text[2 * i]), lo = hex_digit(text[2 * i + 1]);
    if (hi < 0 || lo < 0) return std::nullopt;
    guid[i] = static_cast<uint8_t>(hi * 16 + lo);
  }
  return guid;
}

bool is_sdl_axis(std::string_view name) { return std::find(kAxes.begin(), kAxes.end(), name) != kAxes.end(); }
bool is_sdl_button(std::string_view name) {
  return std::find(kButtons.begin(), kButtons.end(), name) != kButtons.end();
}

std::string sdl_names() {
  std::string out;
  for (const auto n : kAxes) out += (out.empty() ? "" : ", ") + std::string(n);
  for (const auto n : kButtons) out += ", " + std::string(n);
  return out;
}

std::optional<SdlMapping> parse_sdl_mapping(std::string_view line, std::string* error) {
  std::string why;
  auto fail = [&](std::string message) -> std::optional<SdlMapping> {
    if (error) *error = std::move(message);
    return std::nullopt;
  };
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  const auto c1 = line.find(',');
  const auto c2 = c1 == std::string_view::npos ? c1 : line.find(',', c1 + 1);
  if (c2 == std::string_view::npos) return fail("expected GUID,NAME,MAPPING...");
  SdlMapping m;
  // "xinput": SDL's mapping for any XInput device on Windows, no device GUID.
  const bool xinput = line.substr(0, c1) == "xinput";
  const auto guid = xinput ? SdlGuid{} : parse_sdl_guid(line.substr(0, c1));
  if (!guid) return fail("GUID '" + std::string(line.substr(0, c1)) + "' is not 32 hex digits");
  m.guid = *guid;
  m.name = line.substr(c1 + 1, c2 - c1 - 1);
  std::string_view rest = line.substr(c2 + 1);
  while (!rest.empty()) {
    const auto comma = rest.find(',');
    const std::string_view item = rest.substr(0, comma);
    rest = comma == std::string_view::npos ? std::string_view() : rest.substr(comma + 1);
    if (item.empty()) continue;
    const auto colon = item.find(':');
    if (colon == std::string_view::npos) return fail("element '" + std::string(item) + "' has no ':'");
    const std::string_view key = item.substr(0, colon), value = item.substr(colon + 1);
    if (key == "platform") m.platform = value;
    else if (key == "hint" || key == "sdk>=" || key == "sdk<=" || key == "crc") continue;  // SDL's qualifiers
    else if (!parse_element(key, value, m, why)) return fail(why);
  }
  return m;
}

SdlControllerDb SdlControllerDb::load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot read");
  std::ostringstream text;
  text << in.rdbuf();
  return parse(text.str(), path);
}

SdlControllerDb SdlControllerDb::parse(std::string_view text, const std::string& file) {
  SdlControllerDb db;
  db.file_ = file;
  int line_no = 0;
  while (!text.empty()) {
    const auto nl = text.find('\n');
    std::string_view line = text.substr(0, nl);
    text = nl == std::string_view::npos ? std::string_view() : text.substr(nl + 1);
    ++line_no;
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.remove_suffix(1);
    if (line.empty() || line.front() == '#') continue;
    std::string error;
    auto mapping = parse_sdl_mapping(line, &error);
    if (!mapping) {
      db.problems_.push_back(file + ":" + std::to_string(line_no) + ": " + error);
      continue;
    }
    mapping->line = line_no;
    db.mappings_.push_back(std::move(*mapping));
  }
  return db;
}

std::size_t SdlControllerDb::count_platform(std::string_view platform) const {
  return static_cast<std::size_t>(
      std::count_if(mappings_.begin(), mappings_.end(), [&](const SdlMapping& m) { return m.platform == platform; }));
}

const SdlMapping* SdlControllerDb::find_linux(uint16_t bus, uint16_t vendor, uint16_t product,
                                              uint16_t version) const {
  const SdlGuid device = sdl_linux_guid(bus, vendor, product, version);
  const SdlMapping* exact = nullptr;
  const SdlMapping* loose = nullptr;
  for (const SdlMapping& m : mappings_) {
    if (m.platform != "Linux") continue;
    if (same_device(m.guid, device, true)) exact = &m;
    else if (!loose && same_device(m.guid, device, false)) loose = &m;
  }
  return exact ? exact : loose;
}

}  // namespace rise::firmware_protocol
