#include "hil/io/host_port.hpp"

#include <charconv>
#include <utility>

namespace rise::hil::io {
namespace {

bool is_hex_digit(char c) {
  return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F');
}

bool is_alnum(char c) {
  return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
}

std::optional<HostPort> failed(std::string* error, std::string why) {
  if (error != nullptr) *error = std::move(why);
  return std::nullopt;
}

// A name or an IPv4 address; in brackets, an IPv6 address.
bool valid_host(std::string_view host, bool bracketed) {
  for (char c : host) {
    const bool ok = bracketed ? (is_hex_digit(c) || c == ':' || c == '.')
                              : (is_alnum(c) || c == '.' || c == '-' || c == '_');
    if (!ok) return false;
  }
  return true;
}

// Only digits (std::stoi would take "80x" as 80, "-1", " 8"), at most 65535.
std::optional<uint16_t> parse_port(std::string_view text) {
  if (text.empty() || text.size() > 5) return std::nullopt;
  for (char c : text) {
    if (c < '0' || c > '9') return std::nullopt;
  }
  uint32_t value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc{} || end != text.data() + text.size() || value > 65535) return std::nullopt;
  return static_cast<uint16_t>(value);
}

}  // namespace

std::optional<HostPort> parse_host_port(std::string_view text, std::string* error, const HostPortRules& rules) {
  std::string_view host;
  std::string_view port_text;
  bool has_port = true;
  const bool bracketed = !text.empty() && text.front() == '[';
  if (bracketed) {
    const size_t close = text.find(']');
    if (close == std::string_view::npos) return failed(error, "unterminated '[' in the host");
    host = text.substr(1, close - 1);
    const std::string_view after = text.substr(close + 1);
    if (after.empty()) {
      has_port = false;
    } else if (after.front() != ':') {
      return failed(error, "expected ':PORT' after ']'");
    } else {
      port_text = after.substr(1);
    }
  } else {
    const size_t colon = text.rfind(':');
    has_port = colon != std::string_view::npos;
    host = text.substr(0, colon);
    if (has_port) port_text = text.substr(colon + 1);
  }

  if (host.empty()) return failed(error, "missing host (HOST:PORT)");
  if (!bracketed && host.find(':') != std::string_view::npos) {
    return failed(error, "an IPv6 host must be in brackets ([::1]:PORT)");
  }
  if (!valid_host(host, bracketed)) {
    return failed(error, "host '" + std::string(host) + "' has an invalid character");
  }

  HostPort result{std::string(host), rules.default_port};
  if (!has_port) {
    if (rules.default_port == 0) return failed(error, "missing ':PORT' after the host");
    return result;
  }
  const auto port = parse_port(port_text);
  if (!port || (*port == 0 && !rules.any_port)) {
    return failed(error, "port '" + std::string(port_text) + "' is not a number " + (rules.any_port ? "0" : "1") +
                             "..65535");
  }
  result.port = *port;
  return result;
}

std::string format_host_port(std::string_view host, uint16_t port) {
  std::string text;
  if (host.find(':') != std::string_view::npos) {
    text.append("[").append(host).append("]");
  } else {
    text.append(host);
  }
  return text.append(":").append(std::to_string(port));
}

}  // namespace rise::hil::io
