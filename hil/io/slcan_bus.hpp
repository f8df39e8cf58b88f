#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <string>

#include "hil/io/can_bus.hpp"
#include "hil/io/can_url.hpp"
#include "hil/io/posix_io.hpp"

namespace rise::hil::io {

/// slcan://PATH?bitrate=N: a Lawicel serial-line CAN adapter (CANable /
/// candleLight slcan firmware, USBtin, Lawicel CANUSB; what Linux's slcand
/// speaks). Classic CAN only. One thread may send while another receives;
/// reopen() may run from either (it waits for a receive in progress to end).
class SlcanBus final : public CanBus {
 public:
  /// How long reopen() waits for the adapter's answer to each command.
  static constexpr int kCommandTimeoutMs = 500;
  /// How long send() waits for room in the tty's output buffer.
  static constexpr int kSendTimeoutMs = 100;
  /// Longest valid line: `T` + 8 id digits + DLC + 16 data digits + 4
  /// timestamp digits. Longer lines are dropped and counted.
  static constexpr size_t kMaxLineLength = 30;

  /// Does not open the port: call reopen().
  SlcanBus(std::string url, SlcanAddress address);
  /// Closes the CAN channel (`C\r`, not waiting for the answer) and the port.
  ~SlcanBus() override;
  SlcanBus(const SlcanBus&) = delete;
  SlcanBus& operator=(const SlcanBus&) = delete;

  /// Writes `tIIILDD..\r` (`T`, `r`, `R` for extended and remote frames).
  /// Invalid for FD, error and malformed frames; Error in listen-only mode;
  /// Disconnected when the port is closed or went away. No allocation, no
  /// throw: safe in the cyclic path.
  IoStatus send(const CanFrame& frame) override;
  /// Waits up to timeout_ms (0 = poll) for the next received frame line.
  /// Skips OK/BELL answers and `z`/`Z` transmit acknowledgements; counts and
  /// skips malformed and over-long lines. timestamp_us comes from the
  /// adapter's millisecond clock when timestamps=1, else from the host
  /// clock. Disconnected on hang-up (EIO/ENXIO/POLLHUP). No allocation, no throw.
  IoStatus receive(CanFrame& frame, int timeout_ms) override;
  /// Opens the port (raw, URL's baud), then `C`, `Sn`, `Z1` when
  /// timestamps=1, and `O` (`L` when listen_only=1), each answered by `\r`.
  /// Ok; Disconnected (no such device, or it hung up); Timeout (an answer
  /// missing for kCommandTimeoutMs); Error (a BELL answer, not a tty, no
  /// permission). Blocks up to ~4 × kCommandTimeoutMs: not for the cyclic path.
  IoStatus reopen() override;
  bool is_open() const override { return open_.load(); }
  const std::string& url() const override { return url_; }
  std::string last_error() const override { return error_.get(); }

  /// Lines skipped since construction: malformed or longer than kMaxLineLength.
  uint64_t garbage_lines() const { return garbage_lines_.load(); }
  /// BELL answers since the channel opened (the adapter refused a frame).
  uint64_t error_replies() const { return error_replies_.load(); }

 private:
  enum class Token { Line, Ok, Bell, None };

  IoStatus open_port_locked();
  IoStatus command_locked(const char* command, bool need_ok);
  IoStatus read_more_locked(int timeout_ms);
  Token next_token_locked();
  bool parse_line_locked(CanFrame& frame);
  int64_t adapter_time_us_locked(unsigned stamp_ms);
  void drop_port(const char* what, int err);

  const std::string url_;
  const SlcanAddress address_;
  // Lock order: receive_mutex_ before send_mutex_. fd_ changes only with both held.
  std::mutex receive_mutex_;
  std::mutex send_mutex_;
  int fd_ = -1;
  std::atomic<bool> open_{false};
  bool resync_ = false;  // guarded by send_mutex_: a cut line must be ended first
  std::atomic<uint64_t> garbage_lines_{0};
  std::atomic<uint64_t> error_replies_{0};
  // Byte stream → lines; guarded by receive_mutex_.
  std::array<char, 256> input_{};
  size_t input_begin_ = 0;
  size_t input_end_ = 0;
  std::array<char, kMaxLineLength> line_{};
  size_t line_length_ = 0;
  bool line_ready_ = false;  // line_ holds a whole line, handed out by next_token_locked
  bool line_too_long_ = false;
  // Adapter clock (ms, wraps at 60000) anchored to the host clock.
  bool have_stamp_ = false;
  unsigned last_stamp_ms_ = 0;
  int64_t last_stamp_us_ = 0;
  int64_t last_host_us_ = 0;
  detail::ErrorText error_;
};

}  // namespace rise::hil::io
