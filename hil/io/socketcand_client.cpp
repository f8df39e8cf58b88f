#include "hil/io/socketcand_client.hpp"

#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>

namespace rise::hil::io {

using detail::Clock;
using socketcand::MessageKind;

SocketcandClient::SocketcandClient(std::string url, SocketcandAddress address)
    : url_(std::move(url)), address_(std::move(address)) {}

SocketcandClient::~SocketcandClient() { detail::close_fd(fd_); }

IoStatus SocketcandClient::send(const CanFrame& frame) {
  socketcand::MessageBuffer message;
  const size_t length = socketcand::format_send(frame, message);
  if (length == 0) return IoStatus::Invalid;
  std::lock_guard lock(send_mutex_);
  if (!connected_.load()) return IoStatus::Disconnected;
  size_t written = 0;
  const IoStatus status = detail::write_all(fd_, message.data(), length, kSendTimeoutMs, written);
  if (status == IoStatus::Ok) return IoStatus::Ok;
  if (status == IoStatus::Timeout && written == 0) {
    error_.set("%s: send: server does not read (socket buffer full for %d ms)", url_.c_str(),
               kSendTimeoutMs);
    return IoStatus::Timeout;
  }
  drop_connection("send", status == IoStatus::Timeout ? ETIMEDOUT : errno);
  return IoStatus::Disconnected;
}

IoStatus SocketcandClient::receive(CanFrame& frame, int timeout_ms) {
  std::lock_guard lock(receive_mutex_);
  if (!connected_.load()) return IoStatus::Disconnected;
  const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms < 0 ? 0 : timeout_ms);
  for (;;) {
    while (const auto text = parser_.next()) {
      const socketcand::Message message = socketcand::parse_message(*text);
      if (message.kind == MessageKind::Frame) {
        frame = message.frame;
        return IoStatus::Ok;
      }
      if (message.kind == MessageKind::Malformed || message.kind == MessageKind::Error) {
        ++protocol_errors_;
      }
    }
    const IoStatus status = read_more_locked(detail::remaining_ms(deadline));
    if (status == IoStatus::Timeout) return IoStatus::Timeout;
    if (status != IoStatus::Ok) {
      drop_connection("receive", errno);
      return IoStatus::Disconnected;
    }
  }
}

IoStatus SocketcandClient::reopen() {
  std::scoped_lock lock(receive_mutex_, send_mutex_);
  IoStatus status = connect_locked();
  if (status == IoStatus::Ok) status = handshake_locked();
  if (status != IoStatus::Ok) {
    detail::close_fd(fd_);
    return status;
  }
  error_.clear();
  connected_.store(true);
  return IoStatus::Ok;
}

IoStatus SocketcandClient::connect_locked() {
  connected_.store(false);
  detail::close_fd(fd_);
  parser_.clear();

  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_NUMERICSERV;
  char port[8];
  std::snprintf(port, sizeof port, "%u", static_cast<unsigned>(address_.port));
  addrinfo* found = nullptr;
  const int rc = ::getaddrinfo(address_.host.c_str(), port, &hints, &found);
  if (rc != 0) {
    error_.set("%s: cannot resolve host '%s': %s", url_.c_str(), address_.host.c_str(),
               ::gai_strerror(rc));
    return IoStatus::Disconnected;
  }
  for (const addrinfo* ai = found; ai != nullptr && fd_ < 0; ai = ai->ai_next) {
    int fd = ::socket(ai->ai_family, ai->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, ai->ai_protocol);
    if (fd < 0) {
      error_.set("%s: socket: %s", url_.c_str(), detail::errno_text(errno));
      continue;
    }
    int err = 0;
    if (::connect(fd, ai->ai_addr, ai->ai_addrlen) != 0) {
      err = errno;
      if (err == EINPROGRESS) {
        const IoStatus ready = detail::wait_fd(fd, POLLOUT, kConnectTimeoutMs);
        socklen_t size = sizeof err;
        if (ready == IoStatus::Timeout) {
          err = ETIMEDOUT;
        } else if (ready != IoStatus::Ok || ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &size) != 0) {
          err = errno;
        }
      }
    }
    if (err != 0) {
      error_.set("%s: connect: %s", url_.c_str(), detail::errno_text(err));
      detail::close_fd(fd);
      continue;
    }
    fd_ = fd;
  }
  ::freeaddrinfo(found);
  if (fd_ < 0) return IoStatus::Disconnected;
  // Frames are small and latency matters more than segment count.
  const int on = 1;
  ::setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &on, sizeof on);
  return IoStatus::Ok;
}

IoStatus SocketcandClient::handshake_locked() {
  // doc/protocol.md: `< hi >`, then `< open BUS >` → `< ok >` (mode BCM),
  // then `< rawmode >` → `< ok >` (every frame of the bus is forwarded).
  IoStatus status = expect_locked(MessageKind::Hi, "< hi >");
  if (status != IoStatus::Ok) return status;
  char command[64];
  const int length = std::snprintf(command, sizeof command, "< open %s >", address_.bus.c_str());
  size_t written = 0;
  status = detail::write_all(fd_, command, static_cast<size_t>(length), kHandshakeTimeoutMs, written);
  if (status != IoStatus::Ok) {
    error_.set("%s: sending < open >: %s", url_.c_str(), detail::errno_text(errno));
    return status == IoStatus::Timeout ? status : IoStatus::Disconnected;
  }
  status = expect_locked(MessageKind::Ok, "< ok > to < open >");
  if (status != IoStatus::Ok) return status;
  static constexpr char kRawmode[] = "< rawmode >";
  status = detail::write_all(fd_, kRawmode, sizeof kRawmode - 1, kHandshakeTimeoutMs, written);
  if (status != IoStatus::Ok) {
    error_.set("%s: sending < rawmode >: %s", url_.c_str(), detail::errno_text(errno));
    return status == IoStatus::Timeout ? status : IoStatus::Disconnected;
  }
  return expect_locked(MessageKind::Ok, "< ok > to < rawmode >");
}

IoStatus SocketcandClient::expect_locked(MessageKind kind, const char* what) {
  const auto deadline = Clock::now() + std::chrono::milliseconds(kHandshakeTimeoutMs);
  for (;;) {
    while (const auto text = parser_.next()) {
      const socketcand::Message message = socketcand::parse_message(*text);
      if (message.kind == kind) return IoStatus::Ok;
      if (message.kind == MessageKind::Error) {
        error_.set("%s: server refused (waiting for %s): %.*s", url_.c_str(), what,
                   static_cast<int>(message.text.size()), message.text.data());
        return IoStatus::Error;
      }
    }
    if (Clock::now() >= deadline) {
      error_.set("%s: no %s within %d ms", url_.c_str(), what, kHandshakeTimeoutMs);
      return IoStatus::Timeout;
    }
    const IoStatus status = read_more_locked(detail::remaining_ms(deadline));
    if (status == IoStatus::Timeout) continue;
    if (status != IoStatus::Ok) {
      error_.set("%s: connection lost waiting for %s%s%s", url_.c_str(), what,
                 errno != 0 ? ": " : "", errno != 0 ? detail::errno_text(errno) : "");
      return IoStatus::Disconnected;
    }
  }
}

IoStatus SocketcandClient::read_more_locked(int timeout_ms) {
  const IoStatus ready = detail::wait_fd(fd_, POLLIN, timeout_ms);
  if (ready != IoStatus::Ok) return ready;
  const std::span<char> space = parser_.free_space();
  const ssize_t n = ::recv(fd_, space.data(), space.size(), MSG_DONTWAIT);
  if (n > 0) {
    parser_.commit(static_cast<size_t>(n));
    return IoStatus::Ok;
  }
  if (n == 0) {
    errno = 0;  // orderly close by the server
    return IoStatus::Disconnected;
  }
  if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return IoStatus::Ok;
  return IoStatus::Disconnected;
}

void SocketcandClient::drop_connection(const char* what, int err) {
  // Only reopen() closes fd_ (it holds both locks); shutdown wakes the other
  // thread. The first side to notice names the cause.
  if (!connected_.exchange(false)) return;
  ::shutdown(fd_, SHUT_RDWR);
  if (err == 0) {
    error_.set("%s: %s: server closed the connection", url_.c_str(), what);
  } else {
    error_.set("%s: %s: %s", url_.c_str(), what, detail::errno_text(err));
  }
}

}  // namespace rise::hil::io
