#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "hil/io/can_bus.hpp"
#include "hil/io/can_url.hpp"
#include "hil/io/frame_queue.hpp"
#include "hil/io/posix_io.hpp"

namespace rise::hil::io {

/// socketcand+listen://HOST:PORT/BUS: serves one bus to any number of
/// socketcand clients (python-can's "socketcand" interface, Kayak,
/// socketcandcl, SocketcandClient), as linux-can's socketcand does for a
/// kernel bus. A background thread accepts clients and runs the handshake
/// (`< hi >`, `< open BUS >` → `< ok >`, `< rawmode >` → `< ok >`), each
/// reply written only after its request arrived and with its own write:
/// python-can 4.1 reads each with a single recv() and compares it exactly.
/// send() and receive() are thread-safe and never block each other.
class SocketcandServer final : public CanBus {
 public:
  static constexpr size_t kReceiveQueueCapacity = 4096;

  /// Does not listen: call reopen().
  SocketcandServer(std::string url, SocketcandAddress address);
  /// Stops the thread and closes every connection.
  ~SocketcandServer() override;
  SocketcandServer(const SocketcandServer&) = delete;
  SocketcandServer& operator=(const SocketcandServer&) = delete;

  /// Writes `< frame >` (`< fdframe >`, `< rtr >`, `< error >`) to every
  /// client in raw mode, one write per client; a frame with timestamp_us 0
  /// is stamped with the send time. A client whose socket buffer is full
  /// misses the frame (counted in dropped_to_clients()); one whose
  /// connection failed is closed. Ok with no client (nobody listens on the
  /// bus). Disconnected when not listening. No allocation, no throw.
  IoStatus send(const CanFrame& frame) override;
  /// Waits up to timeout_ms (0 = poll) for a frame a client sent with
  /// `< send >`, `< fdsend >` or `< sendrtr >`, stamped with its arrival time.
  IoStatus receive(CanFrame& frame, int timeout_ms) override;
  /// Binds and listens if not listening yet (keeping the port bound first,
  /// so clients find it again). Ok or Error; last_error() is "HOST:PORT:
  /// address in use" when another server listens there. Not for the cyclic path.
  IoStatus reopen() override;
  bool is_open() const override { return listening_.load(); }
  const std::string& url() const override { return url_; }
  std::string last_error() const override { return error_.get(); }

  /// The bound TCP port (the chosen one when the URL asked for 0); 0 when
  /// not listening.
  uint16_t port() const { return listening_.load() ? port_.load() : 0; }
  /// Clients connected and in raw mode for settle_ms (the ones send() reaches).
  size_t client_count() const;
  /// Frames not written to some client because its socket buffer was full.
  uint64_t dropped_to_clients() const { return dropped_to_clients_.load(); }
  /// Frames from clients lost because receive() was not called often enough.
  uint64_t dropped_from_clients() const { return inbound_.dropped(); }

 private:
  struct Peer;
  void run();
  void accept_clients();
  void serve(Peer& peer);
  void handle_locked(Peer& peer, std::string_view text);
  void reply_locked(Peer& peer, const char* data, size_t length);
  void stop();

  const std::string url_;
  const SocketcandAddress address_;
  std::mutex lifecycle_mutex_;  // reopen() and the destructor
  int listen_fd_ = -1;
  int wake_fd_ = -1;  // eventfd that ends the thread's poll()
  std::atomic<bool> listening_{false};
  std::atomic<bool> stopping_{false};
  std::atomic<uint16_t> port_{0};
  std::thread thread_;

  // Peers are added and removed by the thread only, with peers_mutex_ held;
  // send() writes to them with the same mutex held.
  mutable std::mutex peers_mutex_;
  std::vector<std::unique_ptr<Peer>> peers_;

  FrameQueue inbound_{kReceiveQueueCapacity};
  std::atomic<uint64_t> dropped_to_clients_{0};
  detail::ErrorText error_;
};

}  // namespace rise::hil::io
