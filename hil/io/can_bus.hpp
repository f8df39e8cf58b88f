#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "hil/io/can_frame.hpp"

namespace rise::hil::io {

/// Outcome of one transport call; the cyclic path never throws.
enum class IoStatus {
  Ok,
  Timeout,       ///< nothing to read within the timeout
  Disconnected,  ///< the peer or device went away; reopen() may bring it back
  Invalid,       ///< the frame cannot be carried (e.g. FD on a classic bus)
  Error,         ///< any other OS error; see CanBus::last_error()
};

/// Lower-case name of s ("ok", "timeout", ...); a static string, safe in the cyclic path.
const char* to_string(IoStatus s);

/// A CAN bus, whatever carries it. Backends: socketcan://IFACE,
/// socketcand://HOST:PORT/BUS (client), socketcand+listen://HOST:PORT/BUS
/// (server: serves one bus to socketcand clients), slcan://PATH?bitrate=N (a
/// Lawicel serial-line adapter), replay://LOG (plays a candump/ASC/TRC log),
/// mem://NAME (in process); their URLs in can_url.hpp.
class CanBus {
 public:
  virtual ~CanBus() = default;

  /// Sends one frame. Safe in the cyclic path: does not throw.
  virtual IoStatus send(const CanFrame& frame) = 0;

  /// Waits up to timeout_ms (0 = poll) for one frame. Does not throw.
  virtual IoStatus receive(CanFrame& frame, int timeout_ms) = 0;

  /// Tries to (re)open the underlying device or connection. Does not throw.
  virtual IoStatus reopen() = 0;

  /// True while the transport is usable (socket open / peer connected).
  virtual bool is_open() const = 0;

  /// The URL the bus was opened with.
  virtual const std::string& url() const = 0;

  /// Text of the last OS or protocol error, empty if none.
  virtual std::string last_error() const = 0;
};

/// Opens a bus from a URL. Throws std::invalid_argument for a malformed URL
/// or unknown scheme, std::runtime_error when the first open fails for a
/// scheme that cannot wait for its peer (socketcan with no such interface).
/// A socketcand client whose server is not up yet returns a closed bus that
/// reopen() connects later.
std::unique_ptr<CanBus> open_can_bus(std::string_view url);

/// The TCP port a socketcand+listen:// bus listens on (the bound port when
/// the URL asked for port 0); 0 for any other bus or a server not listening.
uint16_t listening_port(const CanBus& bus);

}  // namespace rise::hil::io
