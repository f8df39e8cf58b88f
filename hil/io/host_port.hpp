#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace rise::hil::io {

/// A TCP endpoint. host is a name, an IPv4 address or an IPv6 address
/// (without the brackets it is written with).
struct HostPort {
  std::string host;
  uint16_t port = 0;
};

/// What parse_host_port() accepts beyond HOST:PORT with PORT 1..65535.
struct HostPortRules {
  bool any_port = false;      ///< PORT 0 allowed: a server asks the kernel for any free port
  uint16_t default_port = 0;  ///< > 0: ":PORT" may be left out and is this
};

/// Parses HOST:PORT or [IPv6]:PORT strictly: HOST not empty (letters,
/// digits, '.', '-', '_'; in brackets hex digits, ':' and '.'), PORT only
/// digits in 1..65535 (0..65535 with rules.any_port). On a mistake returns
/// nullopt and sets *error (when not null) to one line naming it, without the
/// text itself, e.g. "port 'abc' is not a number 1..65535": callers prefix
/// what they parsed (`--listen '127.0.0.1:abc': ...`). Not for the cyclic path.
std::optional<HostPort> parse_host_port(std::string_view text, std::string* error, const HostPortRules& rules = {});

/// HOST:PORT as a user writes it: an IPv6 host in brackets ("[::1]:8080").
std::string format_host_port(std::string_view host, uint16_t port);

}  // namespace rise::hil::io
