#include "hil/io/slcan_bus.hpp"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>

#include "hil/io/slcan_wire.hpp"
#include "msgs/clock.hpp"

// The wire format: slcan_wire.hpp.

namespace rise::hil::io {

using detail::Clock;

namespace {

constexpr int64_t kStampWrapMs = kSlcanStampWrapMs;
// Adapter and host clock further apart than this: the adapter was reset or a
// whole wrap went unseen, so its clock is anchored to the host's again.
constexpr int64_t kResyncUs = 1'000'000;
// How long the destructor waits to hand `C\r` to the tty.
constexpr int kCloseTimeoutMs = 20;

speed_t termios_speed(uint32_t baud) {
  switch (baud) {
    case 9600: return B9600;
    case 19200: return B19200;
    case 38400: return B38400;
    case 57600: return B57600;
    case 115200: return B115200;
    case 230400: return B230400;
    case 460800: return B460800;
    case 500000: return B500000;
    case 576000: return B576000;
    case 921600: return B921600;
    case 1000000: return B1000000;
    case 1152000: return B1152000;
    case 1500000: return B1500000;
    case 2000000: return B2000000;
    case 2500000: return B2500000;
    case 3000000: return B3000000;
    case 3500000: return B3500000;
    case 4000000: return B4000000;
    default: return B0;
  }
}

// The device is gone (USB adapter unplugged, pty peer closed) rather than broken.
bool is_gone(int err) { return err == EIO || err == ENXIO || err == ENODEV || err == ENOENT; }

// write() of all of data to a non-blocking tty, waiting up to timeout_ms for
// room. written tells an intact stream (0) from a cut line; errno is kept.
IoStatus write_tty(int fd, const char* data, size_t len, int timeout_ms, size_t& written) {
  written = 0;
  const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms < 0 ? 0 : timeout_ms);
  while (written < len) {
    const ssize_t n = ::write(fd, data + written, len - written);
    if (n > 0) {
      written += static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      const IoStatus s = detail::wait_fd(fd, POLLOUT, detail::remaining_ms(deadline));
      if (s == IoStatus::Timeout) return s;
      if (s != IoStatus::Ok) return IoStatus::Error;
      continue;
    }
    if (n == 0) errno = EIO;
    return is_gone(errno) ? IoStatus::Disconnected : IoStatus::Error;
  }
  return IoStatus::Ok;
}

}  // namespace

SlcanBus::SlcanBus(std::string url, SlcanAddress address)
    : url_(std::move(url)), address_(std::move(address)) {}

SlcanBus::~SlcanBus() {
  if (open_.load()) {
    size_t written = 0;
    write_tty(fd_, "C\r", 2, kCloseTimeoutMs, written);
  }
  detail::close_fd(fd_);
}

IoStatus SlcanBus::send(const CanFrame& frame) {
  // Classic slcan has no FD and no error frames.
  if (frame.fd || frame.error || !is_well_formed(frame)) return IoStatus::Invalid;
  // [0] is a '\r' that ends a line cut by an earlier timeout (the adapter
  // answers it with BELL and drops the fragment).
  SlcanLineBuffer line;
  const size_t n = format_slcan_line(frame, line);

  std::lock_guard lock(send_mutex_);
  if (!open_.load()) return IoStatus::Disconnected;
  if (address_.listen_only) {
    error_.set("%s: send: the channel is open listen-only", url_.c_str());
    return IoStatus::Error;
  }
  const size_t skip = resync_ ? 0 : 1;
  size_t written = 0;
  const IoStatus status = write_tty(fd_, line.data() + skip, n - skip, kSendTimeoutMs, written);
  if (status == IoStatus::Ok) {
    resync_ = false;
    return IoStatus::Ok;
  }
  if (status == IoStatus::Timeout) {
    resync_ = resync_ || written > 0;
    error_.set("%s: send: adapter does not read (tty buffer full for %d ms)", url_.c_str(),
               kSendTimeoutMs);
    return IoStatus::Timeout;
  }
  if (status == IoStatus::Disconnected) {
    drop_port("send", errno);
    return IoStatus::Disconnected;
  }
  error_.set("%s: send: %s", url_.c_str(), detail::errno_text(errno));
  return IoStatus::Error;
}

IoStatus SlcanBus::receive(CanFrame& frame, int timeout_ms) {
  std::lock_guard lock(receive_mutex_);
  if (!open_.load()) return IoStatus::Disconnected;
  const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms < 0 ? 0 : timeout_ms);
  for (;;) {
    for (Token token = next_token_locked(); token != Token::None; token = next_token_locked()) {
      if (token == Token::Bell) ++error_replies_;
      if (token == Token::Line && parse_line_locked(frame)) return IoStatus::Ok;
    }
    const IoStatus status = read_more_locked(detail::remaining_ms(deadline));
    if (status == IoStatus::Timeout) return IoStatus::Timeout;
    if (status != IoStatus::Ok) {
      drop_port("receive", errno);
      return IoStatus::Disconnected;
    }
  }
}

IoStatus SlcanBus::reopen() {
  std::scoped_lock lock(receive_mutex_, send_mutex_);
  IoStatus status = open_port_locked();
  // Close first: a channel left open (a previous run that died) refuses S.
  // An adapter already closed may answer BELL; either answer is fine.
  if (status == IoStatus::Ok) status = command_locked("C\r", false);
  const char bitrate[] = {'S', static_cast<char>('0' + slcan_bitrate_code(address_.bitrate_bps)),
                          '\r', '\0'};
  if (status == IoStatus::Ok) status = command_locked(bitrate, true);
  if (status == IoStatus::Ok && address_.timestamps) status = command_locked("Z1\r", true);
  if (status == IoStatus::Ok) status = command_locked(address_.listen_only ? "L\r" : "O\r", true);
  if (status != IoStatus::Ok) {
    detail::close_fd(fd_);
    return status;
  }
  error_.clear();
  error_replies_.store(0);
  resync_ = false;
  open_.store(true);
  return IoStatus::Ok;
}

IoStatus SlcanBus::open_port_locked() {
  open_.store(false);
  detail::close_fd(fd_);
  input_begin_ = input_end_ = 0;
  line_length_ = 0;
  line_ready_ = line_too_long_ = false;
  have_stamp_ = false;

  const speed_t speed = termios_speed(address_.baud);
  if (speed == B0) {
    error_.set("%s: baud %u is not a termios rate", url_.c_str(), address_.baud);
    return IoStatus::Error;
  }
  const int fd = ::open(address_.path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    error_.set("%s: open %s: %s", url_.c_str(), address_.path.c_str(), detail::errno_text(err));
    return is_gone(err) ? IoStatus::Disconnected : IoStatus::Error;
  }
  fd_ = fd;
  termios tio{};
  if (::tcgetattr(fd_, &tio) != 0) {
    error_.set("%s: %s is not a serial port: %s", url_.c_str(), address_.path.c_str(),
               detail::errno_text(errno));
    return IoStatus::Error;
  }
  // Raw bytes both ways: no echo, no line editing, no CR/NL translation.
  ::cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;
  ::cfsetispeed(&tio, speed);
  ::cfsetospeed(&tio, speed);
  if (::tcsetattr(fd_, TCSANOW, &tio) != 0) {
    const int err = errno;
    error_.set("%s: tcsetattr: %s", url_.c_str(), detail::errno_text(err));
    return is_gone(err) ? IoStatus::Disconnected : IoStatus::Error;
  }
  // Whatever the adapter sent before we came is stale.
  ::tcflush(fd_, TCIOFLUSH);
  return IoStatus::Ok;
}

IoStatus SlcanBus::command_locked(const char* command, bool need_ok) {
  const size_t length = std::strlen(command);
  const int shown = static_cast<int>(length) - 1;  // without '\r'
  size_t written = 0;
  IoStatus status = write_tty(fd_, command, length, kCommandTimeoutMs, written);
  if (status != IoStatus::Ok) {
    error_.set("%s: sending %.*s: %s", url_.c_str(), shown, command,
               status == IoStatus::Timeout ? "tty buffer full" : detail::errno_text(errno));
    return status;
  }
  const auto deadline = Clock::now() + std::chrono::milliseconds(kCommandTimeoutMs);
  for (;;) {
    // Frame lines of a channel left open are skipped here.
    for (Token token = next_token_locked(); token != Token::None; token = next_token_locked()) {
      if (token == Token::Ok) return IoStatus::Ok;
      if (token == Token::Bell) {
        if (!need_ok) return IoStatus::Ok;
        error_.set("%s: adapter refused %.*s (BELL)", url_.c_str(), shown, command);
        return IoStatus::Error;
      }
    }
    if (Clock::now() >= deadline) {
      if (!need_ok) return IoStatus::Ok;
      error_.set("%s: no answer to %.*s within %d ms", url_.c_str(), shown, command,
                 kCommandTimeoutMs);
      return IoStatus::Timeout;
    }
    status = read_more_locked(detail::remaining_ms(deadline));
    if (status == IoStatus::Timeout) continue;
    if (status != IoStatus::Ok) {
      const int err = errno;
      error_.set("%s: adapter hung up waiting for the answer to %.*s%s%s", url_.c_str(), shown,
                 command, err != 0 ? ": " : "", err != 0 ? detail::errno_text(err) : "");
      return IoStatus::Disconnected;
    }
  }
}

IoStatus SlcanBus::read_more_locked(int timeout_ms) {
  const IoStatus ready = detail::wait_fd(fd_, POLLIN, timeout_ms);
  if (ready != IoStatus::Ok) return ready;
  const ssize_t n = ::read(fd_, input_.data(), input_.size());
  if (n > 0) {
    input_begin_ = 0;
    input_end_ = static_cast<size_t>(n);
    return IoStatus::Ok;
  }
  if (n == 0) {
    errno = 0;  // hung up: a tty in raw mode reads 0 only after the other side closed
    return IoStatus::Disconnected;
  }
  if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return IoStatus::Ok;
  return IoStatus::Disconnected;
}

SlcanBus::Token SlcanBus::next_token_locked() {
  if (line_ready_) {
    line_ready_ = false;
    line_length_ = 0;
  }
  while (input_begin_ < input_end_) {
    const char c = input_[input_begin_++];
    if (c == '\a') return Token::Bell;
    if (c == '\r' || c == '\n') {
      if (line_too_long_) {
        line_too_long_ = false;
        line_length_ = 0;
        ++garbage_lines_;
        continue;
      }
      if (line_length_ == 0) {
        // '\n' after '\r' (some firmwares end lines with both) is no answer.
        if (c == '\r') return Token::Ok;
        continue;
      }
      line_ready_ = true;
      return Token::Line;
    }
    if (line_length_ == line_.size()) {
      line_too_long_ = true;
    } else if (!line_too_long_) {
      line_[line_length_++] = c;
    }
  }
  return Token::None;
}

bool SlcanBus::parse_line_locked(CanFrame& frame) {
  const std::string_view line(line_.data(), line_length_);
  // Transmit acknowledgements of CANUSB-like adapters (after t and T).
  if (line == "z" || line == "Z") return false;
  const std::optional<SlcanLine> parsed = parse_slcan_line(line);
  if (!parsed) {
    ++garbage_lines_;
    return false;
  }
  frame = parsed->frame;
  frame.timestamp_us = address_.timestamps && parsed->stamp_ms >= 0
                           ? adapter_time_us_locked(static_cast<unsigned>(parsed->stamp_ms))
                           : msgs::wall_us();
  return true;
}

int64_t SlcanBus::adapter_time_us_locked(unsigned stamp_ms) {
  // The first stamp anchors the adapter clock to the host's; later ones step
  // from the previous by the adapter's own delta, so frame spacing has the
  // adapter's precision. Gaps over 60 s add the whole wraps the host saw.
  const int64_t host_us = msgs::wall_us();
  int64_t stamp_us = host_us;
  if (have_stamp_) {
    const int64_t delta_ms = (static_cast<int64_t>(stamp_ms) - last_stamp_ms_ + kStampWrapMs) % kStampWrapMs;
    const int64_t unseen_us = host_us - last_host_us_ - delta_ms * 1000;
    const int64_t wraps = unseen_us > 0 ? (unseen_us + kStampWrapMs * 500) / (kStampWrapMs * 1000) : 0;
    const int64_t stepped_us = last_stamp_us_ + (delta_ms + wraps * kStampWrapMs) * 1000;
    const int64_t apart_us = stepped_us > host_us ? stepped_us - host_us : host_us - stepped_us;
    if (apart_us <= kResyncUs) stamp_us = stepped_us;
  }
  have_stamp_ = true;
  last_stamp_ms_ = stamp_ms;
  last_stamp_us_ = stamp_us;
  last_host_us_ = host_us;
  return stamp_us;
}

void SlcanBus::drop_port(const char* what, int err) {
  // Only reopen() closes fd_ (it holds both locks); the first side to notice
  // names the cause.
  if (!open_.exchange(false)) return;
  if (err == 0) {
    error_.set("%s: %s: adapter hung up", url_.c_str(), what);
  } else {
    error_.set("%s: %s: %s", url_.c_str(), what, detail::errno_text(err));
  }
}

}  // namespace rise::hil::io
