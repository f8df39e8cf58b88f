#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace rise::io {

/// One CAN_RAW_FILTER entry: a frame passes when (frame id & mask) ==
/// (id & mask) and its id kind (11 or 29 bit) is the filter's.
struct CanIdFilter {
  uint32_t id = 0;
  uint32_t mask = 0;
  bool extended = false;
};

/// socketcan://IFACE[?filter=ID:MASK[,ID:MASK...]] with ID and MASK in hex;
/// an ID written with 8 digits or above 7FF is a 29-bit id (as candump).
struct SocketCanAddress {
  std::string interface;
  std::vector<CanIdFilter> filters;  ///< empty: every frame
};

/// socketcand://HOST:PORT/BUS (client) or socketcand+listen://HOST:PORT/BUS
/// [?settle_ms=N] (server; PORT 0 = any free port). HOST may be a name, an
/// IPv4 address or a bracketed IPv6 address.
struct SocketcandAddress {
  bool listen = false;
  std::string host;
  uint16_t port = 0;
  std::string bus;
  /// Server only: how long after its `< rawmode >` a client gets no frames,
  /// so that python-can's client, which reads that `< ok >` with a single
  /// recv() and compares it exactly, does not see a frame glued to it.
  int settle_ms = 200;
};

/// mem://NAME: an in-process bus shared by every bus opened with NAME.
struct MemAddress {
  std::string name;
};

using CanAddress = std::variant<SocketCanAddress, SocketcandAddress, MemAddress>;

/// Parses a CAN bus URL (schemes above). Throws std::invalid_argument whose
/// message names the URL and what is wrong with it. Not for the cyclic path.
CanAddress parse_can_url(std::string_view url);

}  // namespace rise::io
