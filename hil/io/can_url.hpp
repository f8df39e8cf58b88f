#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace rise::hil::io {

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

/// slcan://PATH?bitrate=N[&listen_only=0|1][&timestamps=0|1][&baud=N]: a
/// Lawicel serial-line adapter at an absolute device path. bitrate is one of
/// the Lawicel S0..S8 rates; baud (default 115200) is a termios rate that
/// USB CDC-ACM adapters ignore.
struct SlcanAddress {
  std::string path;
  uint32_t bitrate_bps = 0;
  bool listen_only = false;
  bool timestamps = false;
  uint32_t baud = 115200;
};

/// Lawicel `Sn` code (0..8) of a CAN bitrate in bit/s, -1 when slcan has none.
int slcan_bitrate_code(uint32_t bitrate_bps);

/// replay://PATH[?speed=X][&loop=N][&start=S][&stop=S][&ids=ID,ID...][&channel=NAME][&fast=0|1]:
/// plays a CAN log file (see replay_bus.hpp). speed > 0 scales time (2 =
/// twice as fast); loop = extra passes (0 = once, -1 = forever); start/stop
/// in seconds from the first record; ids in hex (frames whose id is one of
/// them, 11 or 29 bit alike); channel as the log names it ("can0", "1");
/// step=1: a frame only when ReplayBus::step() allows one (no timing).
struct ReplayAddress {
  std::string path;
  double speed = 1.0;
  int loop = 0;
  double start_s = 0.0;
  double stop_s = -1.0;  ///< < 0: to the end
  std::vector<uint32_t> ids;  ///< empty: every id
  std::string channel;        ///< empty: every channel
  bool fast = false;
  bool step = false;
};

using CanAddress =
    std::variant<SocketCanAddress, SocketcandAddress, MemAddress, SlcanAddress, ReplayAddress>;

/// Parses a CAN bus URL (schemes above). Throws std::invalid_argument whose
/// message names the URL and what is wrong with it. Not for the cyclic path.
CanAddress parse_can_url(std::string_view url);

}  // namespace rise::hil::io
