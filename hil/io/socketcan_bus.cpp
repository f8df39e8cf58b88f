#include "hil/io/socketcan_bus.hpp"

#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <vector>

#include "msgs/clock.hpp"

namespace rise::hil::io {

using detail::Clock;

namespace {

// The kernel reports a lost link on the socket: ENETDOWN when the interface
// went down (raw.c: NETDEV_DOWN), ENODEV when it was removed (NETDEV_UNREGISTER).
bool is_link_loss(int err) { return err == ENETDOWN || err == ENODEV || err == ENXIO; }

void to_frame(const canfd_frame& in, bool fd, CanFrame& out) {
  out = CanFrame{};
  if ((in.can_id & CAN_ERR_FLAG) != 0) {
    // linux/can/error.h: the id holds the error class, data[0..7] the details.
    out.error = true;
    out.id = in.can_id & CAN_ERR_MASK;
  } else {
    out.extended = (in.can_id & CAN_EFF_FLAG) != 0;
    out.remote = (in.can_id & CAN_RTR_FLAG) != 0;
    out.id = in.can_id & (out.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
  }
  out.fd = fd;
  if (fd) {
    out.brs = (in.flags & CANFD_BRS) != 0;
    out.esi = (in.flags & CANFD_ESI) != 0;
  }
  out.len = std::min<uint8_t>(in.len, fd ? CANFD_MAX_DLEN : CAN_MAX_DLEN);
  if (!out.remote) std::memcpy(out.data.data(), in.data, out.len);
}

}  // namespace

SocketCanBus::SocketCanBus(std::string url, SocketCanAddress address)
    : url_(std::move(url)), address_(std::move(address)) {}

SocketCanBus::~SocketCanBus() { detail::close_fd(fd_); }

IoStatus SocketCanBus::os_failure(const char* call, int err) {
  error_.set("%s: %s: %s", url_.c_str(), call, detail::errno_text(err));
  if (is_link_loss(err)) {
    open_.store(false);
    return IoStatus::Disconnected;
  }
  return IoStatus::Error;
}

IoStatus SocketCanBus::fail_locked(IoStatus status, const char* call, int err) {
  error_.set("%s: %s: %s", url_.c_str(), call, detail::errno_text(err));
  return status;
}

IoStatus SocketCanBus::reopen() {
  std::scoped_lock lock(receive_mutex_, send_mutex_);
  open_.store(false);
  detail::close_fd(fd_);

  int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    const int err = errno;
    if (err == EAFNOSUPPORT || err == EPROTONOSUPPORT) {
      error_.set("%s: this kernel has no CAN support (socket: %s)", url_.c_str(),
                 detail::errno_text(err));
      return IoStatus::Error;
    }
    return fail_locked(IoStatus::Error, "socket", err);
  }

  ifreq ifr{};
  std::strncpy(ifr.ifr_name, address_.interface.c_str(), IFNAMSIZ - 1);
  if (::ioctl(fd, SIOCGIFINDEX, &ifr) < 0) {
    const int err = errno;
    detail::close_fd(fd);
    error_.set("%s: no such CAN interface '%s' (SIOCGIFINDEX: %s)", url_.c_str(),
               address_.interface.c_str(), detail::errno_text(err));
    return err == ENODEV ? IoStatus::Disconnected : IoStatus::Error;
  }
  const int ifindex = ifr.ifr_ifindex;

  // raw_bind() accepts a down interface and only flags ENETDOWN on the socket
  // afterwards, so a bus "opened" now would report Disconnected on its first
  // call; say it here, and a reconnect loop retries until `ip link set up`.
  if (::ioctl(fd, SIOCGIFFLAGS, &ifr) == 0 && (ifr.ifr_flags & IFF_UP) == 0) {
    detail::close_fd(fd);
    error_.set("%s: CAN interface '%s' is down", url_.c_str(), address_.interface.c_str());
    return IoStatus::Disconnected;
  }

  // can-utils and socketcand: enable FD only when the interface's MTU says
  // it carries FD frames (CANFD_MTU, or more for CAN XL); an older kernel
  // without CAN_RAW_FD_FRAMES (ENOPROTOOPT) stays classic.
  bool fd_mode = false;
  if (::ioctl(fd, SIOCGIFMTU, &ifr) == 0 && ifr.ifr_mtu >= static_cast<int>(CANFD_MTU)) {
    const int on = 1;
    fd_mode = ::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) == 0;
  }

  const can_err_mask_t error_classes = CAN_ERR_MASK;
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &error_classes, sizeof error_classes) != 0) {
    const int err = errno;
    detail::close_fd(fd);
    return fail_locked(IoStatus::Error, "setsockopt(CAN_RAW_ERR_FILTER)", err);
  }
  const int on = 1;
  if (::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMP, &on, sizeof on) != 0) {
    const int err = errno;
    detail::close_fd(fd);
    return fail_locked(IoStatus::Error, "setsockopt(SO_TIMESTAMP)", err);
  }
  if (!address_.filters.empty()) {
    // CAN_EFF_FLAG in the mask makes a filter match only its own id kind;
    // CAN_RTR_FLAG is left out so data and remote frames both pass.
    std::vector<can_filter> filters;
    for (const CanIdFilter& f : address_.filters) {
      filters.push_back({f.id | (f.extended ? CAN_EFF_FLAG : 0U), f.mask | CAN_EFF_FLAG});
    }
    if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, filters.data(),
                     static_cast<socklen_t>(filters.size() * sizeof(can_filter))) != 0) {
      const int err = errno;
      detail::close_fd(fd);
      return fail_locked(IoStatus::Error, "setsockopt(CAN_RAW_FILTER)", err);
    }
  }

  sockaddr_can address{};
  address.can_family = AF_CAN;
  address.can_ifindex = ifindex;
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    const int err = errno;
    detail::close_fd(fd);
    // raw_bind(): ENODEV also when the interface is not of type ARPHRD_CAN.
    error_.set("%s: '%s' is gone or not a CAN interface (bind: %s)", url_.c_str(),
               address_.interface.c_str(), detail::errno_text(err));
    return err == ENODEV ? IoStatus::Disconnected : IoStatus::Error;
  }

  fd_ = fd;
  fd_enabled_.store(fd_mode);
  open_.store(true);
  error_.clear();
  return IoStatus::Ok;
}

IoStatus SocketCanBus::send(const CanFrame& frame) {
  if (frame.error || !is_well_formed(frame)) return IoStatus::Invalid;
  std::lock_guard lock(send_mutex_);
  if (!open_.load()) return IoStatus::Disconnected;
  if (frame.fd && !fd_enabled_.load()) return IoStatus::Invalid;

  // struct can_frame is the first CAN_MTU bytes of struct canfd_frame
  // (linux/can.h), so one buffer serves both; the size tells them apart.
  canfd_frame out{};
  out.can_id = frame.id | (frame.extended ? CAN_EFF_FLAG : 0U) | (frame.remote ? CAN_RTR_FLAG : 0U);
  out.len = frame.len;
  if (frame.fd) {
    out.flags = static_cast<uint8_t>((frame.brs ? CANFD_BRS : 0) | (frame.esi ? CANFD_ESI : 0));
  }
  if (!frame.remote) std::memcpy(out.data, frame.data.data(), frame.len);
  const size_t size = frame.fd ? CANFD_MTU : CAN_MTU;

  bool waited = false;
  for (;;) {
    const ssize_t n = ::send(fd_, &out, size, MSG_DONTWAIT | MSG_NOSIGNAL);
    if (n == static_cast<ssize_t>(size)) return IoStatus::Ok;
    if (n >= 0) return fail_locked(IoStatus::Error, "send (short write)", EIO);
    const int err = errno;
    if (err == EINTR) continue;
    if ((err == EAGAIN || err == EWOULDBLOCK) && !waited) {
      waited = true;
      if (detail::wait_fd(fd_, POLLOUT, kSendTimeoutMs) == IoStatus::Ok) continue;
      return fail_locked(IoStatus::Timeout, "send", EAGAIN);
    }
    // ENOBUFS: the driver's tx queue is full (the bus is busy or nobody acks);
    // poll() does not signal when it drains, so report and let the caller decide.
    if (err == ENOBUFS || err == EAGAIN || err == EWOULDBLOCK) {
      return fail_locked(IoStatus::Timeout, "send", err);
    }
    return os_failure("send", err);
  }
}

IoStatus SocketCanBus::receive(CanFrame& frame, int timeout_ms) {
  std::lock_guard lock(receive_mutex_);
  if (!open_.load()) return IoStatus::Disconnected;
  const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms < 0 ? 0 : timeout_ms);
  for (;;) {
    canfd_frame in{};
    sockaddr_can from{};
    iovec iov{&in, sizeof in};
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timeval)) + CMSG_SPACE(sizeof(uint32_t))];
    msghdr msg{};
    msg.msg_name = &from;
    msg.msg_namelen = sizeof from;
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof control;

    const ssize_t n = ::recvmsg(fd_, &msg, MSG_DONTWAIT);
    if (n < 0) {
      const int err = errno;
      if (err == EINTR) continue;
      if (err == EAGAIN || err == EWOULDBLOCK) {
        const IoStatus ready = detail::wait_fd(fd_, POLLIN, detail::remaining_ms(deadline));
        if (ready == IoStatus::Ok) continue;
        if (ready == IoStatus::Timeout) return IoStatus::Timeout;
        return os_failure("poll", errno);
      }
      return os_failure("recvmsg", err);
    }
    const bool fd = n == static_cast<ssize_t>(CANFD_MTU);
    if (!fd && n != static_cast<ssize_t>(CAN_MTU)) continue;  // not a frame this socket asked for

    to_frame(in, fd, frame);
    frame.timestamp_us = 0;
    for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMP) {
        timeval tv{};
        std::memcpy(&tv, CMSG_DATA(c), sizeof tv);
        frame.timestamp_us = static_cast<int64_t>(tv.tv_sec) * 1'000'000 + tv.tv_usec;
      }
    }
    if (frame.timestamp_us == 0) frame.timestamp_us = msgs::wall_us();
    return IoStatus::Ok;
  }
}

}  // namespace rise::hil::io
