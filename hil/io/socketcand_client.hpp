#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>

#include "hil/io/can_bus.hpp"
#include "hil/io/can_url.hpp"
#include "hil/io/posix_io.hpp"
#include "hil/io/socketcand_wire.hpp"

namespace rise::hil::io {

/// socketcand://HOST:PORT/BUS: a client of a socketcand server (linux-can
/// socketcand, or socketcand+listen:// of this library) in raw mode.
/// One thread may send while another receives; reopen() may run from
/// either (it waits for a receive in progress to end).
class SocketcandClient final : public CanBus {
 public:
  /// How long reopen() waits for the TCP connection, then for each step of
  /// the handshake (`< hi >`, `< ok >` to open, `< ok >` to rawmode).
  static constexpr int kConnectTimeoutMs = 200;
  static constexpr int kHandshakeTimeoutMs = 1000;
  /// How long send() waits for room in the socket buffer.
  static constexpr int kSendTimeoutMs = 100;

  /// Does not connect: call reopen().
  SocketcandClient(std::string url, SocketcandAddress address);
  ~SocketcandClient() override;
  SocketcandClient(const SocketcandClient&) = delete;
  SocketcandClient& operator=(const SocketcandClient&) = delete;

  /// Writes `< send >` (`< fdsend >`, `< sendrtr >`). Invalid for error
  /// frames; Disconnected when not connected or the server went away; a
  /// message cut by a timeout closes the connection (the stream would be
  /// corrupt). No allocation, no throw: safe in the cyclic path.
  IoStatus send(const CanFrame& frame) override;
  /// Waits up to timeout_ms (0 = poll) for the next `< frame >`,
  /// `< fdframe >`, `< rtr >` or `< error CLASS TIME >` (error frame);
  /// skips garbage and other messages. Disconnected when the server closed
  /// the connection. No allocation, no throw.
  IoStatus receive(CanFrame& frame, int timeout_ms) override;
  /// Connects (non-blocking, kConnectTimeoutMs) and does the handshake.
  /// Ok, Disconnected (server not there / closed), Timeout (handshake
  /// stalled) or Error (server refused the bus). Not for the cyclic path
  /// (name resolution, up to ~3 s).
  IoStatus reopen() override;
  bool is_open() const override { return connected_.load(); }
  const std::string& url() const override { return url_; }
  std::string last_error() const override { return error_.get(); }

  /// Messages skipped since construction: malformed, or `< error >` replies.
  uint64_t protocol_errors() const { return protocol_errors_.load(); }

 private:
  IoStatus connect_locked();
  IoStatus handshake_locked();
  IoStatus expect_locked(socketcand::MessageKind kind, const char* what);
  IoStatus read_more_locked(int timeout_ms);
  void drop_connection(const char* what, int err);

  const std::string url_;
  const SocketcandAddress address_;
  // Lock order: receive_mutex_ before send_mutex_. fd_ changes only with both held.
  std::mutex receive_mutex_;
  std::mutex send_mutex_;
  int fd_ = -1;
  std::atomic<bool> connected_{false};
  std::atomic<uint64_t> protocol_errors_{0};
  socketcand::StreamParser parser_;  // guarded by receive_mutex_
  detail::ErrorText error_;
};

}  // namespace rise::hil::io
