#pragma once

#include <atomic>
#include <mutex>
#include <string>

#include "hil/io/can_bus.hpp"
#include "hil/io/can_url.hpp"
#include "hil/io/posix_io.hpp"

namespace rise::hil::io {

/// socketcan://IFACE: a Linux CAN_RAW socket bound to one interface
/// (can0, vcan0, slcan0 after slcand). CAN FD frames are enabled when the
/// interface's MTU is CANFD_MTU (72), else the socket is classic; error
/// frames are delivered with frame.error set (all classes, CAN_ERR_MASK);
/// receive times come from the kernel (SO_TIMESTAMP). One thread may send
/// while another receives.
class SocketCanBus final : public CanBus {
 public:
  /// How long send() waits for room in the socket's send buffer.
  static constexpr int kSendTimeoutMs = 10;

  /// Does not open: call reopen().
  SocketCanBus(std::string url, SocketCanAddress address);
  ~SocketCanBus() override;
  SocketCanBus(const SocketCanBus&) = delete;
  SocketCanBus& operator=(const SocketCanBus&) = delete;

  /// Invalid for error frames, FD frames on a classic interface and frames
  /// that are not well formed; Timeout when the driver's queue is full
  /// (ENOBUFS); Disconnected when the interface is down or gone. No
  /// allocation, no throw: safe in the cyclic path.
  IoStatus send(const CanFrame& frame) override;
  /// Waits up to timeout_ms (0 = poll). Disconnected when the interface went
  /// down (ENETDOWN) or away (ENODEV). No allocation, no throw.
  IoStatus receive(CanFrame& frame, int timeout_ms) override;
  /// Creates, configures and binds a new socket. Error with "no CAN
  /// support" when the kernel has no CAN stack, Disconnected when the
  /// interface does not exist or is down. Not for the cyclic path.
  IoStatus reopen() override;
  bool is_open() const override { return open_.load(); }
  const std::string& url() const override { return url_; }
  std::string last_error() const override { return error_.get(); }

  /// True when the socket carries CAN FD frames (interface MTU 72).
  bool fd_enabled() const { return fd_enabled_.load(); }

 private:
  IoStatus fail_locked(IoStatus status, const char* call, int err);
  IoStatus os_failure(const char* call, int err);

  const std::string url_;
  const SocketCanAddress address_;
  // Lock order: receive_mutex_ before send_mutex_. fd_ changes only with both held.
  std::mutex receive_mutex_;
  std::mutex send_mutex_;
  int fd_ = -1;
  std::atomic<bool> open_{false};
  std::atomic<bool> fd_enabled_{false};
  detail::ErrorText error_;
};

}  // namespace rise::hil::io
