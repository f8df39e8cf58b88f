#include "hil/io/modbus_url.hpp"

#include <charconv>
#include <stdexcept>
#include <utility>

#include "hil/io/host_port.hpp"

namespace rise::hil::io {
namespace {

[[noreturn]] void fail(std::string_view url, const std::string& what) {
  throw std::invalid_argument("modbus URL '" + std::string(url) + "': " + what);
}

int to_int(std::string_view url, std::string_view key, std::string_view text, int lo, int hi) {
  int v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || v < lo || v > hi)
    fail(url, std::string(key) + "=" + std::string(text) + " must be an integer " + std::to_string(lo) + ".." +
                  std::to_string(hi));
  return v;
}

}  // namespace

bool is_modbus_url(std::string_view url) { return url.rfind("modbus+", 0) == 0; }

ModbusAddress parse_modbus_url(std::string_view url) {
  ModbusAddress a;
  const auto sep = url.find("://");
  if (sep == std::string_view::npos) fail(url, "no scheme (modbus+tcp://, modbus+rtu://, ...)");
  const std::string_view scheme = url.substr(0, sep);
  if (scheme == "modbus+tcp" || scheme == "modbus+tcp-listen") {
    a.kind = ModbusAddress::Kind::Tcp;
  } else if (scheme == "modbus+rtu" || scheme == "modbus+rtu-listen") {
    a.kind = ModbusAddress::Kind::Rtu;
  } else {
    fail(url, "unknown scheme '" + std::string(scheme) + "'");
  }
  a.listen = scheme.ends_with("-listen");
  std::string_view rest = url.substr(sep + 3);
  std::string_view query;
  if (const auto q = rest.find('?'); q != std::string_view::npos) {
    query = rest.substr(q + 1);
    rest = rest.substr(0, q);
  }
  if (a.kind == ModbusAddress::Kind::Tcp) {
    // PORT 0 (any free port) only for a server; without :PORT, 502.
    std::string error;
    auto endpoint = parse_host_port(rest, &error, {.any_port = a.listen, .default_port = a.port});
    if (!endpoint) fail(url, error);
    a.host = std::move(endpoint->host);
    a.port = endpoint->port;
  } else {
    if (rest.empty() || rest[0] != '/') fail(url, "no device path (modbus+rtu:///dev/ttyUSB0)");
    a.device = std::string(rest);
  }
  while (!query.empty()) {
    const auto amp = query.find('&');
    const std::string_view item = query.substr(0, amp);
    query = amp == std::string_view::npos ? std::string_view{} : query.substr(amp + 1);
    const auto eq = item.find('=');
    if (eq == std::string_view::npos) fail(url, "query item '" + std::string(item) + "' is not KEY=VALUE");
    const std::string_view key = item.substr(0, eq), value = item.substr(eq + 1);
    const bool rtu = a.kind == ModbusAddress::Kind::Rtu;
    if (key == "unit") {
      a.unit = to_int(url, key, value, 0, 247);
    } else if (key == "timeout_ms") {
      a.timeout_ms = to_int(url, key, value, 1, 60000);
    } else if (rtu && key == "baud") {
      a.baud = to_int(url, key, value, 300, 4000000);
    } else if (rtu && key == "parity") {
      if (value != "N" && value != "E" && value != "O") fail(url, "parity must be N, E or O");
      a.parity = value[0];
    } else if (rtu && key == "data") {
      a.data_bits = to_int(url, key, value, 5, 8);
    } else if (rtu && key == "stop") {
      a.stop_bits = to_int(url, key, value, 1, 2);
    } else {
      fail(url, "unknown option '" + std::string(key) + "'");
    }
  }
  return a;
}

}  // namespace rise::hil::io
