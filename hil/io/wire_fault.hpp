#pragma once

// Wire faults: decorators around a real transport that lose, hold back or
// damage what crosses the wire, as a bad cable, a babbling node or a dying
// slave would. They sit under the daemon's decode, so everything above
// (E2E checks, staleness, bus-off handling, failsafe) reacts as it would to
// the real thing. Faults are injected from another thread (the daemon's LCM
// thread): every call takes the decorator's mutex.
//
// | kind             | effect (probability `value`, default 1)                                  |
// |------------------|---------------------------------------------------------------------------|
// | can_drop         | a received frame is lost (alive counters skip; all lost → stale)           |
// | can_delay        | every received frame is held back `rate` ms (default 50)                  |
// | can_corrupt      | a received frame has a data bit flipped (the E2E CRC fails → bad frame)    |
// | can_bus_off      | a bus-off error frame, nothing until the end, then a "restarted" one      |
// | modbus_exception | a request answers exception code `rate` (default 4, server device failure) |
// | modbus_timeout   | a request gets no answer (counted as a timeout)                           |
// Randomness is splitmix64 of (seed, frame/request count): one seed, one sequence.

#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hil/io/can_bus.hpp"
#include "hil/io/modbus_link.hpp"

namespace rise::hil::io {

enum class WireFaultKind { CanDrop, CanDelay, CanCorrupt, CanBusOff, ModbusException, ModbusTimeout };
const char* to_string(WireFaultKind kind);
std::optional<WireFaultKind> parse_wire_fault_kind(std::string_view name);
inline bool is_can_fault(WireFaultKind k) {
  return k == WireFaultKind::CanDrop || k == WireFaultKind::CanDelay || k == WireFaultKind::CanCorrupt ||
         k == WireFaultKind::CanBusOff;
}

struct WireFault {
  std::string id;
  WireFaultKind kind = WireFaultKind::CanDrop;
  double value = 0.0;    ///< probability per frame/request (0 or ≥ 1: always)
  double rate = 0.0;     ///< can_delay: ms; modbus_exception: the code
  uint64_t seed = 0;
  int64_t start_us = 0;  ///< steady-clock µs (msgs::monotonic_us)
  int64_t end_us = 0;    ///< 0 = until cleared
  bool active(int64_t now_us) const { return now_us >= start_us && (end_us == 0 || now_us < end_us); }
};

/// The faults of one transport, shared by both decorators.
class WireFaultSet {
 public:
  /// Adds (or replaces, by id) a fault.
  void inject(WireFault fault);
  /// Removes `id` ("" = every one) and the ended; returns how many named were removed.
  std::size_t clear(const std::string& id, int64_t now_us);
  /// The faults in effect at now_us.
  std::vector<WireFault> active(int64_t now_us) const;

 protected:
  // Does an active fault of `kind` hit the n-th frame/request? Caller holds mutex_.
  const WireFault* hits(WireFaultKind kind, int64_t now_us, uint64_t n) const;
  mutable std::mutex mutex_;
  std::vector<WireFault> faults_;
};

/// A CanBus whose received frames pass through the wire faults. Sending is
/// untouched (the console's side of the wire is the one faulted).
class FaultyCanBus : public CanBus, public WireFaultSet {
 public:
  explicit FaultyCanBus(std::unique_ptr<CanBus> inner);

  IoStatus send(const CanFrame& frame) override { return inner_->send(frame); }
  IoStatus receive(CanFrame& frame, int timeout_ms) override;
  IoStatus reopen() override { return inner_->reopen(); }
  bool is_open() const override { return inner_->is_open(); }
  const std::string& url() const override { return inner_->url(); }
  std::string last_error() const override { return inner_->last_error(); }

  /// Frames the faults dropped, corrupted, delayed so far.
  int64_t dropped() const;
  int64_t corrupted() const;

 private:
  std::unique_ptr<CanBus> inner_;
  std::deque<std::pair<int64_t, CanFrame>> held_;  // can_delay: (due µs, frame)
  uint64_t frames_ = 0;
  int64_t dropped_ = 0;
  int64_t corrupted_ = 0;
  bool bus_off_ = false;  // a bus-off frame was delivered; a restart frame is owed at the end
};

/// A ModbusLink whose requests can time out or answer an exception.
class FaultyModbusLink : public ModbusLink, public WireFaultSet {
 public:
  explicit FaultyModbusLink(std::unique_ptr<ModbusLink> inner);
  ModbusResult read_coils(uint16_t address, std::span<uint8_t> bits) override;
  ModbusResult read_discrete_inputs(uint16_t address, std::span<uint8_t> bits) override;
  ModbusResult read_holding_registers(uint16_t address, std::span<uint16_t> registers) override;
  ModbusResult read_input_registers(uint16_t address, std::span<uint16_t> registers) override;
  ModbusResult write_coils(uint16_t address, std::span<const uint8_t> bits) override;
  ModbusResult write_registers(uint16_t address, std::span<const uint16_t> registers) override;
  bool is_open() const override { return inner_->is_open(); }
  ModbusStatus reopen() override { return inner_->reopen(); }
  void close() override { inner_->close(); }
  std::string last_error() const override { return inner_->last_error(); }

 private:
  // The fault's answer to the next request, if one hits it.
  std::optional<ModbusResult> faulted();
  std::unique_ptr<ModbusLink> inner_;
  uint64_t requests_ = 0;
};

}  // namespace rise::hil::io
