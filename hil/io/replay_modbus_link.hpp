#pragma once

// replay://FILE.modbus.log?speed=1&loop=0&start=S&stop=S&fast=0 — a
// ModbusLink that answers the daemon's polls from a recorded Modbus
// transaction trace (hil/io/modbus_trace.hpp, what `rise-hild --record`
// writes) or a pcap/pcapng of Modbus/TCP (its transactions turned into
// such a trace, hil/io/modbus_capture.hpp), so that the daemon cannot tell
// the replay from the slave.
//
// Time. The replay time runs from the window's start: r = t_first + start +
// (now − t0) · speed, with t_first the trace's first record and t0 the
// steady-clock time of the link's first request (read, write or reopen).
// It is anchored once, as ReplayBus anchors a CAN log: no drift accumulates
// and a slow poll does not delay the next one.
//
// Reads. A read is answered with the recorded answer of the same request
// (function, address, count) that is the latest at or before r, by request
// time (before the first such request: the first): its values when it was
// ok, otherwise its result — a timeout (returned after its recorded rtt_us /
// speed, as a silent slave takes the master's timeout), an exception with
// its code, a CRC error, an error. A request that the trace never holds is
// answered with exception 02 (illegal data address), as a slave without
// those addresses answers.
//
// The link. The trace says when the recorded link was down: from the
// answer of a request that left it closed with any result but a timeout
// (the slave went away), a "reopen failed", a "close" or a "link closed"
// line, to the next "reopen ok" or "link open". While it was down a request
// returns Disconnected and closes this link, and reopen() fails: the daemon
// sees the loss, backs off and reconnects as it did with the slave. A
// timeout that closed the link (libmodbus over TCP restarts the connection
// so that a late answer cannot be taken for the next one) closes this link
// too, and reopen() succeeds at once, as the recorded one did.
//
// Writes are accepted and dropped (counted in writes_dropped()): Ok while
// the recorded link was up, Disconnected while it was down.
//
// The end. Past the window's end (the last record, or stop=) and the loops
// the link closes: every request returns Disconnected and reopen() fails
// from then on, like a slave that is gone, so the panel fails safe as on a
// lost slave and stays so. loop=N plays the window N more times (-1:
// forever), each pass one mean request gap after the previous one.
//
// fast=1: no waiting; time moves by the requests instead of the clock. Each
// read takes the recorded answer of its request that follows the replay
// time (which jumps to it), a timeout is answered at once, and reopen() of
// a link that was down jumps to when the recorded link came up.
//
// Threading: one thread, as every ModbusLink; the counters may be read
// from another.

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "hil/io/can_url.hpp"
#include "hil/io/modbus_link.hpp"
#include "hil/io/modbus_trace.hpp"

namespace rise::hil::io {

/// True when the URL's scheme is replay:// (a CAN log or a Modbus trace).
bool is_replay_url(std::string_view url);

class ReplayModbusLink final : public ModbusLink {
 public:
  /// Reads the whole trace. Throws std::runtime_error naming the path when
  /// it cannot be opened, "path:line: what" for a line that is not a trace
  /// line, and when it holds no transaction, the traffic of several sources
  /// or an empty window.
  ReplayModbusLink(std::string url, ReplayAddress address);

  /// The recorded answer of the same request at the replay time, as the
  /// header says; no throw, no allocation; a recorded timeout sleeps its
  /// rtt_us / speed (real time only).
  ModbusResult read_coils(uint16_t address, std::span<uint8_t> bits) override;
  ModbusResult read_discrete_inputs(uint16_t address, std::span<uint8_t> bits) override;
  ModbusResult read_holding_registers(uint16_t address, std::span<uint16_t> registers) override;
  ModbusResult read_input_registers(uint16_t address, std::span<uint16_t> registers) override;
  /// Dropped and counted: Ok while the recorded link was up. No throw.
  ModbusResult write_coils(uint16_t address, std::span<const uint8_t> bits) override;
  ModbusResult write_registers(uint16_t address, std::span<const uint16_t> registers) override;

  bool is_open() const override { return open_; }
  /// Ok when the recorded link was up at the replay time, Disconnected when
  /// it was down or the replay has ended.
  ModbusStatus reopen() override;
  void close() override { open_ = false; }
  std::string last_error() const override { return open_ ? "" : "the recorded link was down (or the replay ended)"; }

  /// The window in the trace's clock (µs since the epoch): its first and last instant.
  struct Window {
    int64_t begin_us = 0;
    int64_t end_us = 0;
  };
  Window window() const { return {window_begin_us_, window_end_us_}; }
  /// The trace time that the steady-clock time `steady_us` (µs since the
  /// steady clock's epoch, as msgs::monotonic_us()) plays, within the pass it
  /// falls in; nullopt before the first request. With fast=1: the trace time
  /// of the last request.
  std::optional<int64_t> trace_time_us(int64_t steady_us) const;
  /// The trace time the last request was answered from.
  int64_t last_request_trace_us() const { return last_request_us_; }
  /// Writes accepted and dropped.
  int64_t writes_dropped() const { return writes_dropped_; }
  /// Reads the trace holds no request for (answered with exception 02).
  int64_t unknown_requests() const { return unknown_requests_; }
  /// True once the replay is past its end (and its loops).
  bool ended() const { return ended_; }
  const std::string& url() const { return url_; }

 private:
  struct Answer {
    int64_t time_us = 0;
    int64_t rtt_us = 0;
    ModbusResult result;
    bool closed = false;
    std::size_t first_value = 0;  // into values_
  };
  struct Request {
    ModbusFunction function = ModbusFunction::ReadInputRegisters;
    uint16_t address = 0;
    uint16_t count = 0;
    std::vector<Answer> answers;  // by time
  };
  struct LinkEvent {
    int64_t time_us = 0;
    bool up = false;
  };

  template <typename T>
  ModbusResult read(ModbusFunction function, uint16_t address, std::span<T> out);
  ModbusResult write();
  // The elapsed replay time (µs from the window's start, loops included) now.
  int64_t elapsed_now();
  int64_t in_pass(int64_t elapsed) const;  // → trace time
  bool past_end(int64_t elapsed) const;
  int64_t beyond_end() const;  // the first elapsed time past the last pass
  // Moves the replay to `elapsed`: its trace time into trace_us; false, with
  // the link closed, when that is past the end or the recorded link was down.
  bool reach(int64_t elapsed, int64_t& trace_us);
  bool link_up(int64_t trace_us) const;
  const Request* find(ModbusFunction function, uint16_t address, std::size_t count) const;
  const Answer& latest(const Request& request, int64_t trace_us) const;
  // fast=1: the elapsed time of the first of `times` after the replay's (jumping a pass when needed).
  template <typename Times>
  std::optional<int64_t> fast_next(const Times& times, std::size_t size);

  std::string url_;
  ReplayAddress address_;
  std::vector<Request> requests_;
  std::vector<uint16_t> values_;
  std::vector<LinkEvent> link_events_;  // by time
  int64_t window_begin_us_ = 0;
  int64_t window_end_us_ = 0;
  int64_t period_us_ = 1;  // a pass: the window plus one mean request gap

  bool anchored_ = false;
  std::atomic<int64_t> t0_steady_us_{0};
  int64_t fast_elapsed_us_ = 0;
  bool fast_started_ = false;
  std::atomic<bool> open_{true};
  std::atomic<bool> ended_{false};
  std::atomic<int64_t> last_request_us_{0};
  std::atomic<int64_t> writes_dropped_{0};
  std::atomic<int64_t> unknown_requests_{0};
};

/// Opens replay://FILE.modbus.log?speed=&loop=&start=&stop=&fast= (the
/// options of the CAN replay:// but ids, channel and step, which are for
/// CAN logs). Throws std::invalid_argument for a bad URL, std::runtime_error
/// for a file that is no Modbus trace.
std::unique_ptr<ReplayModbusLink> open_modbus_replay(std::string_view url);

}  // namespace rise::hil::io
