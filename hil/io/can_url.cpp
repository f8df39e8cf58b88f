#include "hil/io/can_url.hpp"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <stdexcept>
#include <utility>

#include "hil/io/host_port.hpp"

namespace rise::hil::io {

namespace {

// IFNAMSIZ - 1: the longest Linux interface name.
constexpr size_t kMaxInterfaceName = 15;
// socketcand limits the name in `< open canbus >` to 16 characters (doc/protocol.md).
constexpr size_t kMaxBusName = 16;
constexpr size_t kMaxMemName = 64;
// CAN_RAW_FILTER_MAX in linux/can/raw.h.
constexpr size_t kMaxFilters = 512;
constexpr int kMaxSettleMs = 10'000;

[[noreturn]] void fail(std::string_view url, std::string_view why) {
  std::string text = "invalid CAN bus URL '";
  text.append(url).append("': ").append(why);
  throw std::invalid_argument(text);
}

bool is_hex_digit(char c) {
  return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F');
}

bool is_alnum(char c) {
  return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
}

std::optional<uint32_t> parse_hex(std::string_view text, size_t max_digits) {
  if (text.empty() || text.size() > max_digits) return std::nullopt;
  for (char c : text) {
    if (!is_hex_digit(c)) return std::nullopt;
  }
  uint32_t value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value, 16);
  if (ec != std::errc{} || end != text.data() + text.size()) return std::nullopt;
  return value;
}

std::optional<uint32_t> parse_decimal(std::string_view text, uint32_t max) {
  if (text.empty() || text.size() > 10) return std::nullopt;
  for (char c : text) {
    if (c < '0' || c > '9') return std::nullopt;
  }
  uint64_t value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value, 10);
  if (ec != std::errc{} || end != text.data() + text.size() || value > max) return std::nullopt;
  return static_cast<uint32_t>(value);
}

std::vector<std::string_view> split(std::string_view text, char separator) {
  std::vector<std::string_view> parts;
  for (;;) {
    const size_t at = text.find(separator);
    parts.push_back(text.substr(0, at));
    if (at == std::string_view::npos) return parts;
    text.remove_prefix(at + 1);
  }
}

using QueryItems = std::vector<std::pair<std::string_view, std::string_view>>;

// "a=1&b=2" → {(a,1),(b,2)}; every key must be in allowed and appear once.
QueryItems parse_query(std::string_view url, std::string_view query,
                       std::initializer_list<std::string_view> allowed) {
  QueryItems items;
  if (query.empty()) fail(url, "empty query after '?'");
  for (std::string_view item : split(query, '&')) {
    const size_t eq = item.find('=');
    if (eq == std::string_view::npos || eq == 0) {
      fail(url, "query item '" + std::string(item) + "' is not KEY=VALUE");
    }
    const std::string_view key = item.substr(0, eq);
    bool known = false;
    for (std::string_view a : allowed) known = known || a == key;
    if (!known) {
      std::string why = "unknown query key '" + std::string(key) + "'";
      if (allowed.size() == 0) {
        why += " (this scheme takes none)";
      } else {
        why += " (allowed:";
        for (std::string_view a : allowed) why.append(" ").append(a);
        why += ")";
      }
      fail(url, why);
    }
    for (const auto& [k, v] : items) {
      if (k == key) fail(url, "query key '" + std::string(key) + "' given twice");
    }
    items.emplace_back(key, item.substr(eq + 1));
  }
  return items;
}

// Linux interface names: 1..15 bytes, no '/', ':' or white space, not "." or "..".
void check_interface(std::string_view url, std::string_view name) {
  if (name.empty()) fail(url, "missing interface name (socketcan://IFACE)");
  if (name.size() > kMaxInterfaceName) {
    fail(url, "interface name '" + std::string(name) + "' is longer than 15 characters");
  }
  if (name == "." || name == "..") fail(url, "interface name cannot be '.' or '..'");
  for (char c : name) {
    if (c == '/' || c == ':' || c == ' ' || c == '\t' || c == '\n' || c == '#' ||
        static_cast<unsigned char>(c) < 0x21 || static_cast<unsigned char>(c) > 0x7E) {
      fail(url, "interface name '" + std::string(name) + "' has a character Linux does not allow");
    }
  }
}

CanIdFilter parse_filter(std::string_view url, std::string_view text) {
  const size_t colon = text.find(':');
  if (colon == std::string_view::npos) {
    fail(url, "filter '" + std::string(text) + "' is not ID:MASK (hex)");
  }
  const std::string_view id_text = text.substr(0, colon);
  const auto id = parse_hex(id_text, 8);
  const auto mask = parse_hex(text.substr(colon + 1), 8);
  if (!id || !mask) fail(url, "filter '" + std::string(text) + "' is not ID:MASK (hex)");
  if (*id > 0x1FFFFFFF || *mask > 0x1FFFFFFF) {
    fail(url, "filter '" + std::string(text) + "' exceeds 29 bits");
  }
  CanIdFilter filter;
  filter.id = *id;
  filter.mask = *mask;
  filter.extended = id_text.size() == 8 || *id > 0x7FF;
  if (!filter.extended && *mask > 0x7FF) {
    fail(url, "filter '" + std::string(text) + "': mask exceeds 11 bits for an 11-bit id");
  }
  return filter;
}

SocketCanAddress parse_socketcan(std::string_view url, std::string_view rest) {
  SocketCanAddress address;
  const size_t question = rest.find('?');
  const std::string_view name = rest.substr(0, question);
  check_interface(url, name);
  address.interface = std::string(name);
  if (question == std::string_view::npos) return address;

  for (const auto& [key, value] : parse_query(url, rest.substr(question + 1), {"filter"})) {
    if (value.empty()) fail(url, "empty filter list");
    for (std::string_view item : split(value, ',')) {
      address.filters.push_back(parse_filter(url, item));
    }
    if (address.filters.size() > kMaxFilters) fail(url, "more than 512 filters");
  }
  return address;
}

SocketcandAddress parse_socketcand(std::string_view url, std::string_view rest, bool listen) {
  SocketcandAddress address;
  address.listen = listen;
  const size_t question = rest.find('?');
  const std::string_view query =
      question == std::string_view::npos ? std::string_view{} : rest.substr(question + 1);
  rest = rest.substr(0, question);

  const size_t slash = rest.find('/');
  if (slash == std::string_view::npos) fail(url, "missing /BUS after HOST:PORT");
  const std::string_view authority = rest.substr(0, slash);
  const std::string_view bus = rest.substr(slash + 1);

  // PORT 0 (any free port) only for a server; a client must know where to connect.
  std::string error;
  auto endpoint = parse_host_port(authority, &error, {.any_port = listen});
  if (!endpoint) fail(url, error);
  address.host = std::move(endpoint->host);
  address.port = endpoint->port;

  if (bus.empty()) fail(url, "missing bus name after '/'");
  if (bus.size() > kMaxBusName) {
    fail(url, "bus name '" + std::string(bus) + "' is longer than 16 characters");
  }
  for (char c : bus) {
    // The name travels inside `< open BUS >`: no separators of that protocol.
    if (!(is_alnum(c) || c == '_' || c == '-' || c == '.')) {
      fail(url, "bus name '" + std::string(bus) + "' may hold only letters, digits, '_', '-', '.'");
    }
  }
  address.bus = std::string(bus);

  if (question != std::string_view::npos) {
    const auto items = listen ? parse_query(url, query, {"settle_ms"}) : parse_query(url, query, {});
    for (const auto& [key, value] : items) {
      const auto settle = parse_decimal(value, kMaxSettleMs);
      if (!settle) fail(url, "settle_ms '" + std::string(value) + "' is not a number 0..10000");
      address.settle_ms = static_cast<int>(*settle);
    }
  }
  return address;
}

MemAddress parse_mem(std::string_view url, std::string_view rest) {
  if (rest.find('?') != std::string_view::npos) parse_query(url, rest.substr(rest.find('?') + 1), {});
  if (rest.empty()) fail(url, "missing bus name (mem://NAME)");
  if (rest.size() > kMaxMemName) fail(url, "name is longer than 64 characters");
  for (char c : rest) {
    if (!(is_alnum(c) || c == '_' || c == '-' || c == '.')) {
      fail(url, "name may hold only letters, digits, '_', '-', '.'");
    }
  }
  return MemAddress{std::string(rest)};
}

// The termios rates of <asm-generic/termbits.h> from 9600 up.
constexpr uint32_t kSerialBauds[] = {9600,   19200,   38400,   57600,   115200,  230400,  460800,
                                     500000, 576000,  921600,  1000000, 1152000, 1500000, 2000000,
                                     2500000, 3000000, 3500000, 4000000};

bool parse_flag(std::string_view url, std::string_view key, std::string_view value) {
  if (value == "1") return true;
  if (value != "0") fail(url, std::string(key) + " '" + std::string(value) + "' is not 0 or 1");
  return false;
}

SlcanAddress parse_slcan(std::string_view url, std::string_view rest) {
  SlcanAddress address;
  const size_t question = rest.find('?');
  const std::string_view path = rest.substr(0, question);
  if (path.empty()) fail(url, "missing device path (slcan:///dev/ttyACM0?bitrate=500000)");
  if (path.front() != '/') fail(url, "device path '" + std::string(path) + "' is not absolute");
  for (char c : path) {
    if (static_cast<unsigned char>(c) < 0x21 || static_cast<unsigned char>(c) > 0x7E) {
      fail(url, "device path has a space or control character");
    }
  }
  address.path = std::string(path);
  if (question == std::string_view::npos) fail(url, "missing ?bitrate=N (CAN bit/s)");
  bool have_bitrate = false;
  const auto items =
      parse_query(url, rest.substr(question + 1), {"bitrate", "listen_only", "timestamps", "baud"});
  for (const auto& [key, value] : items) {
    if (key == "bitrate") {
      const auto bitrate = parse_decimal(value, 1'000'000);
      if (!bitrate || slcan_bitrate_code(*bitrate) < 0) {
        fail(url, "bitrate '" + std::string(value) +
                      "' is not an slcan rate (10000 20000 50000 100000 125000 250000 500000 "
                      "800000 1000000)");
      }
      address.bitrate_bps = *bitrate;
      have_bitrate = true;
    } else if (key == "baud") {
      const auto baud = parse_decimal(value, 4'000'000);
      bool known = false;
      for (uint32_t b : kSerialBauds) known = known || (baud && *baud == b);
      if (!known) fail(url, "baud '" + std::string(value) + "' is not a termios rate 9600..4000000");
      address.baud = *baud;
    } else if (key == "listen_only") {
      address.listen_only = parse_flag(url, key, value);
    } else {
      address.timestamps = parse_flag(url, key, value);
    }
  }
  if (!have_bitrate) fail(url, "missing bitrate=N (CAN bit/s)");
  return address;
}

// A finite decimal number (std::strtod syntax, nothing after it).
std::optional<double> parse_real(std::string_view text) {
  if (text.empty() || text.size() > 32) return std::nullopt;
  const std::string copy(text);
  char* end = nullptr;
  const double value = std::strtod(copy.c_str(), &end);
  if (end != copy.c_str() + copy.size() || !std::isfinite(value)) return std::nullopt;
  return value;
}

ReplayAddress parse_replay(std::string_view url, std::string_view rest) {
  ReplayAddress address;
  const size_t question = rest.find('?');
  address.path = std::string(rest.substr(0, question));
  if (address.path.empty()) fail(url, "missing log file path (replay://PATH)");
  if (question == std::string_view::npos) return address;
  const auto items = parse_query(url, rest.substr(question + 1),
                                 {"speed", "loop", "start", "stop", "ids", "channel", "fast", "step"});
  for (const auto& [key, value] : items) {
    const std::string what = std::string(key) + " '" + std::string(value) + "'";
    if (key == "speed") {
      const auto speed = parse_real(value);
      if (!speed || *speed <= 0.0) fail(url, what + " is not a number > 0");
      address.speed = *speed;
    } else if (key == "loop") {
      const auto loop = parse_decimal(value, 1'000'000);
      if (value == "-1") address.loop = -1;
      else if (loop) address.loop = static_cast<int>(*loop);
      else fail(url, what + " is not -1 (forever) or a count >= 0");
    } else if (key == "start" || key == "stop") {
      const auto seconds = parse_real(value);
      if (!seconds || *seconds < 0.0) fail(url, what + " is not seconds >= 0");
      (key == "start" ? address.start_s : address.stop_s) = *seconds;
    } else if (key == "ids") {
      for (std::string_view item : split(value, ',')) {
        const auto id = parse_hex(item, 8);
        if (!id || *id > 0x1FFFFFFF) fail(url, "id '" + std::string(item) + "' is not a hex CAN id");
        address.ids.push_back(*id);
      }
    } else if (key == "channel") {
      if (value.empty()) fail(url, "empty channel");
      address.channel = std::string(value);
    } else if (key == "step") {
      address.step = parse_flag(url, key, value);
    } else {
      address.fast = parse_flag(url, key, value);
    }
  }
  if (address.stop_s >= 0.0 && address.stop_s < address.start_s) fail(url, "stop is before start");
  return address;
}

}  // namespace

int slcan_bitrate_code(uint32_t bitrate_bps) {
  // Lawicel CANUSB manual, command Sn: S0 = 10 kbit/s ... S8 = 1 Mbit/s.
  constexpr uint32_t kRates[] = {10000,  20000,  50000,  100000, 125000,
                                 250000, 500000, 800000, 1000000};
  for (int code = 0; code < 9; ++code) {
    if (kRates[code] == bitrate_bps) return code;
  }
  return -1;
}

CanAddress parse_can_url(std::string_view url) {
  const size_t sep = url.find("://");
  if (sep == std::string_view::npos || sep == 0) {
    fail(url, "expected SCHEME://... with scheme socketcan, socketcand, socketcand+listen, mem, "
              "slcan or replay");
  }
  std::string scheme(url.substr(0, sep));
  for (char& c : scheme) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');  // RFC 3986 3.1
  }
  const std::string_view rest = url.substr(sep + 3);
  if (scheme == "socketcan") return parse_socketcan(url, rest);
  if (scheme == "socketcand") return parse_socketcand(url, rest, false);
  if (scheme == "socketcand+listen") return parse_socketcand(url, rest, true);
  if (scheme == "mem") return parse_mem(url, rest);
  if (scheme == "slcan") return parse_slcan(url, rest);
  if (scheme == "replay") return parse_replay(url, rest);
  fail(url, "unknown scheme '" + scheme +
                "' (known: socketcan, socketcand, socketcand+listen, mem, slcan, replay)");
}

}  // namespace rise::hil::io
