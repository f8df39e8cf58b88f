#include "hil/io/socketcand_server.hpp"

#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <system_error>

#include "hil/io/host_port.hpp"
#include "hil/io/socketcand_wire.hpp"
#include "msgs/clock.hpp"

namespace rise::hil::io {

using detail::Clock;
using socketcand::MessageKind;

namespace {

constexpr char kHi[] = "< hi >";
constexpr char kOk[] = "< ok >";
constexpr char kUnknownCommand[] = "< error unknown command >";

uint16_t bound_port(int fd) {
  sockaddr_storage address{};
  socklen_t size = sizeof address;
  if (::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &size) != 0) return 0;
  if (address.ss_family == AF_INET) {
    return ntohs(reinterpret_cast<const sockaddr_in*>(&address)->sin_port);
  }
  if (address.ss_family == AF_INET6) {
    return ntohs(reinterpret_cast<const sockaddr_in6*>(&address)->sin6_port);
  }
  return 0;
}

}  // namespace

// One TCP client. The connection moves NO_BUS (greeted) → BCM (bus opened)
// → RAW as in socketcand's doc/protocol.md; frames go to RAW clients only.
struct SocketcandServer::Peer {
  enum class State { Greeted, Opened, Raw };
  int fd = -1;
  State state = State::Greeted;
  Clock::time_point raw_since{};
  bool dead = false;                // set under peers_mutex_; the thread closes it
  socketcand::StreamParser parser;  // the thread only
};

SocketcandServer::SocketcandServer(std::string url, SocketcandAddress address)
    : url_(std::move(url)), address_(std::move(address)) {}

SocketcandServer::~SocketcandServer() {
  std::lock_guard lock(lifecycle_mutex_);
  stop();
}

void SocketcandServer::stop() {
  if (thread_.joinable()) {
    stopping_.store(true);
    const uint64_t one = 1;
    [[maybe_unused]] const ssize_t n = ::write(wake_fd_, &one, sizeof one);
    thread_.join();
  }
  listening_.store(false);
  {
    std::lock_guard lock(peers_mutex_);
    for (auto& peer : peers_) detail::close_fd(peer->fd);
    peers_.clear();
  }
  detail::close_fd(listen_fd_);
  detail::close_fd(wake_fd_);
}

IoStatus SocketcandServer::reopen() {
  std::lock_guard lock(lifecycle_mutex_);
  if (listening_.load()) return IoStatus::Ok;
  stop();  // a thread that ended on a poll() error

  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  char port[8];
  // Once bound, keep the port: clients were told this one.
  const uint16_t wanted = port_.load() != 0 ? port_.load() : address_.port;
  std::snprintf(port, sizeof port, "%u", static_cast<unsigned>(wanted));
  addrinfo* found = nullptr;
  const int rc = ::getaddrinfo(address_.host.c_str(), port, &hints, &found);
  if (rc != 0) {
    error_.set("%s: cannot resolve host '%s': %s", url_.c_str(), address_.host.c_str(),
               ::gai_strerror(rc));
    return IoStatus::Error;
  }
  for (const addrinfo* ai = found; ai != nullptr && listen_fd_ < 0; ai = ai->ai_next) {
    int fd = ::socket(ai->ai_family, ai->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, ai->ai_protocol);
    if (fd < 0) {
      error_.set("%s: socket: %s", url_.c_str(), detail::errno_text(errno));
      continue;
    }
    // A restarted server must get its port back while old connections sit in
    // TIME_WAIT. SO_REUSEADDR only: with SO_REUSEPORT a second server would
    // bind the same port and the kernel would split the clients between them.
    const int on = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
    const char* failed = ::bind(fd, ai->ai_addr, ai->ai_addrlen) != 0 ? "bind"
                         : ::listen(fd, SOMAXCONN) != 0              ? "listen"
                                                                      : nullptr;
    if (failed != nullptr) {
      const int failed_errno = errno;
      detail::close_fd(fd);
      // listen() too: two sockets with SO_REUSEADDR may both bind before either listens.
      if (failed_errno == EADDRINUSE) {
        // Another server holds it: not another of the host's addresses either.
        error_.set("%s: address in use", format_host_port(address_.host, wanted).c_str());
        break;
      }
      error_.set("%s: %s: %s", url_.c_str(), failed, detail::errno_text(failed_errno));
      continue;
    }
    listen_fd_ = fd;
  }
  ::freeaddrinfo(found);
  if (listen_fd_ < 0) return IoStatus::Error;

  wake_fd_ = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (wake_fd_ < 0) {
    error_.set("%s: eventfd: %s", url_.c_str(), detail::errno_text(errno));
    detail::close_fd(listen_fd_);
    return IoStatus::Error;
  }
  port_.store(bound_port(listen_fd_));
  stopping_.store(false);
  try {
    thread_ = std::thread([this] { run(); });
  } catch (const std::system_error& e) {
    error_.set("%s: cannot start the server thread: %s", url_.c_str(), e.what());
    detail::close_fd(listen_fd_);
    detail::close_fd(wake_fd_);
    return IoStatus::Error;
  }
  listening_.store(true);
  error_.clear();
  return IoStatus::Ok;
}

IoStatus SocketcandServer::send(const CanFrame& frame) {
  if (!listening_.load()) return IoStatus::Disconnected;
  socketcand::MessageBuffer message;
  const int64_t stamp = frame.timestamp_us != 0 ? frame.timestamp_us : msgs::wall_us();
  const size_t length = socketcand::format_frame(frame, stamp, message);
  if (length == 0) return IoStatus::Invalid;
  const auto now = Clock::now();
  const auto settle = std::chrono::milliseconds(address_.settle_ms);
  std::lock_guard lock(peers_mutex_);
  for (auto& peer : peers_) {
    if (peer->dead || peer->state != Peer::State::Raw || now - peer->raw_since < settle) continue;
    // One send() per message: python-can 4.1 loses a message that a recv() cuts.
    const ssize_t n = ::send(peer->fd, message.data(), length, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n == static_cast<ssize_t>(length)) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      ++dropped_to_clients_;
      continue;
    }
    // Failed or cut mid-message: this client's stream is lost. shutdown()
    // makes the thread see it and close the socket.
    peer->dead = true;
    ::shutdown(peer->fd, SHUT_RDWR);
  }
  return IoStatus::Ok;
}

IoStatus SocketcandServer::receive(CanFrame& frame, int timeout_ms) {
  if (!listening_.load()) return IoStatus::Disconnected;
  return inbound_.pop(frame, timeout_ms) ? IoStatus::Ok : IoStatus::Timeout;
}

size_t SocketcandServer::client_count() const {
  const auto now = Clock::now();
  const auto settle = std::chrono::milliseconds(address_.settle_ms);
  std::lock_guard lock(peers_mutex_);
  size_t count = 0;
  for (const auto& peer : peers_) {
    if (!peer->dead && peer->state == Peer::State::Raw && now - peer->raw_since >= settle) ++count;
  }
  return count;
}

void SocketcandServer::run() {
  std::vector<pollfd> fds;
  std::vector<Peer*> polled;
  while (!stopping_.load()) {
    fds.clear();
    polled.clear();
    fds.push_back({wake_fd_, POLLIN, 0});
    fds.push_back({listen_fd_, POLLIN, 0});
    {
      std::lock_guard lock(peers_mutex_);
      for (auto it = peers_.begin(); it != peers_.end();) {
        if ((*it)->dead) {
          detail::close_fd((*it)->fd);
          it = peers_.erase(it);
        } else {
          fds.push_back({(*it)->fd, POLLIN, 0});
          polled.push_back(it->get());
          ++it;
        }
      }
    }
    if (::poll(fds.data(), fds.size(), -1) < 0) {
      if (errno == EINTR) continue;
      error_.set("%s: poll: %s", url_.c_str(), detail::errno_text(errno));
      listening_.store(false);
      return;
    }
    if (fds[0].revents != 0) {
      uint64_t count = 0;
      [[maybe_unused]] const ssize_t n = ::read(wake_fd_, &count, sizeof count);
    }
    if (fds[1].revents != 0) accept_clients();
    for (size_t i = 0; i < polled.size(); ++i) {
      if (fds[i + 2].revents != 0) serve(*polled[i]);
    }
  }
}

void SocketcandServer::accept_clients() {
  for (;;) {
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EINTR || errno == ECONNABORTED) continue;
      if (errno != EAGAIN && errno != EWOULDBLOCK) {
        error_.set("%s: accept: %s", url_.c_str(), detail::errno_text(errno));
      }
      return;
    }
    const int on = 1;
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &on, sizeof on);
    auto peer = std::make_unique<Peer>();
    peer->fd = fd;
    std::lock_guard lock(peers_mutex_);
    reply_locked(*peer, kHi, sizeof kHi - 1);
    peers_.push_back(std::move(peer));
  }
}

void SocketcandServer::serve(Peer& peer) {
  const std::span<char> space = peer.parser.free_space();
  const ssize_t n = ::recv(peer.fd, space.data(), space.size(), MSG_DONTWAIT);
  if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) return;
  std::lock_guard lock(peers_mutex_);
  if (n <= 0) {
    peer.dead = true;
    return;
  }
  peer.parser.commit(static_cast<size_t>(n));
  while (!peer.dead) {
    const auto text = peer.parser.next();
    if (!text) break;
    handle_locked(peer, *text);
  }
}

void SocketcandServer::handle_locked(Peer& peer, std::string_view text) {
  const socketcand::Message message = socketcand::parse_message(text);
  if (message.kind == MessageKind::Echo) {
    reply_locked(peer, text.data(), text.size());
    return;
  }
  if (peer.state == Peer::State::Greeted) {
    if (message.kind != MessageKind::Open) {
      reply_locked(peer, kUnknownCommand, sizeof kUnknownCommand - 1);
      return;
    }
    if (message.text == address_.bus) {
      peer.state = Peer::State::Opened;
      reply_locked(peer, kOk, sizeof kOk - 1);
      return;
    }
    // doc/protocol.md: the server answers with an error and ends the connection.
    char reply[64];
    const int length = std::snprintf(reply, sizeof reply, "< error no such bus %.*s >",
                                     static_cast<int>(std::min<size_t>(message.text.size(), 16)),
                                     message.text.data());
    reply_locked(peer, reply, static_cast<size_t>(length));
    peer.dead = true;
    ::shutdown(peer.fd, SHUT_WR);
    return;
  }
  switch (message.kind) {
    case MessageKind::Rawmode:
      peer.state = Peer::State::Raw;
      peer.raw_since = Clock::now();
      reply_locked(peer, kOk, sizeof kOk - 1);
      return;
    case MessageKind::Send: {
      CanFrame frame = message.frame;
      frame.timestamp_us = msgs::wall_us();
      inbound_.push(frame);
      return;
    }
    case MessageKind::Malformed:
      // socketcand logs a syntax error and answers nothing.
      return;
    default:
      reply_locked(peer, kUnknownCommand, sizeof kUnknownCommand - 1);
      return;
  }
}

void SocketcandServer::reply_locked(Peer& peer, const char* data, size_t length) {
  const ssize_t n = ::send(peer.fd, data, length, MSG_NOSIGNAL | MSG_DONTWAIT);
  if (n != static_cast<ssize_t>(length)) {
    peer.dead = true;
    ::shutdown(peer.fd, SHUT_RDWR);
  }
}

}  // namespace rise::hil::io
