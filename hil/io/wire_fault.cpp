#include "hil/io/wire_fault.hpp"

#include "hil/io/seeded_draw.hpp"
#include "msgs/clock.hpp"

#include <linux/can/error.h>

#include <algorithm>
#include <chrono>

namespace rise::hil::io {
namespace {

CanFrame error_frame(uint32_t classes) {
  CanFrame f;
  f.error = true;
  f.id = classes;
  f.len = CAN_ERR_DLC;
  return f;
}

}  // namespace

const char* to_string(WireFaultKind kind) {
  switch (kind) {
    case WireFaultKind::CanDrop: return "can_drop";
    case WireFaultKind::CanDelay: return "can_delay";
    case WireFaultKind::CanCorrupt: return "can_corrupt";
    case WireFaultKind::CanBusOff: return "can_bus_off";
    case WireFaultKind::ModbusException: return "modbus_exception";
    case WireFaultKind::ModbusTimeout: return "modbus_timeout";
  }
  return "?";
}

std::optional<WireFaultKind> parse_wire_fault_kind(std::string_view name) {
  for (auto k : {WireFaultKind::CanDrop, WireFaultKind::CanDelay, WireFaultKind::CanCorrupt, WireFaultKind::CanBusOff,
                 WireFaultKind::ModbusException, WireFaultKind::ModbusTimeout})
    if (name == to_string(k)) return k;
  return std::nullopt;
}

void WireFaultSet::inject(WireFault fault) {
  std::lock_guard lock(mutex_);
  std::erase_if(faults_, [&](const WireFault& f) { return f.id == fault.id; });
  faults_.push_back(std::move(fault));
}

std::size_t WireFaultSet::clear(const std::string& id, int64_t now_us) {
  std::lock_guard lock(mutex_);
  const std::size_t named = std::erase_if(faults_, [&](const WireFault& f) { return id.empty() || f.id == id; });
  std::erase_if(faults_, [&](const WireFault& f) { return f.end_us != 0 && f.end_us <= now_us; });
  return named;
}

std::vector<WireFault> WireFaultSet::active(int64_t now_us) const {
  std::lock_guard lock(mutex_);
  std::vector<WireFault> out;
  for (const auto& f : faults_)
    if (f.active(now_us)) out.push_back(f);
  return out;
}

const WireFault* WireFaultSet::hits(WireFaultKind kind, int64_t now_us, uint64_t n) const {
  for (const auto& f : faults_) {
    if (f.kind != kind || !f.active(now_us)) continue;
    if (f.value <= 0.0 || f.value >= 1.0 || seeded_uniform(f.seed, n) < f.value) return &f;
  }
  return nullptr;
}

FaultyCanBus::FaultyCanBus(std::unique_ptr<CanBus> inner) : inner_(std::move(inner)) {}

int64_t FaultyCanBus::dropped() const {
  std::lock_guard lock(mutex_);
  return dropped_;
}

int64_t FaultyCanBus::corrupted() const {
  std::lock_guard lock(mutex_);
  return corrupted_;
}

IoStatus FaultyCanBus::receive(CanFrame& frame, int timeout_ms) {
  const int64_t deadline_us = msgs::monotonic_us() + int64_t{timeout_ms} * 1000;
  for (;;) {
    int64_t now = msgs::monotonic_us();
    {
      std::lock_guard lock(mutex_);
      const bool bus_off = hits(WireFaultKind::CanBusOff, now, 0) != nullptr;
      if (bus_off != bus_off_) {
        // The controller's own error frames: bus-off on entry, restarted at the end.
        bus_off_ = bus_off;
        frame = error_frame(bus_off ? CAN_ERR_BUSOFF : CAN_ERR_RESTARTED);
        frame.timestamp_us = 0;
        return IoStatus::Ok;
      }
      if (!held_.empty() && held_.front().first <= now) {
        frame = held_.front().second;
        held_.pop_front();
        return IoStatus::Ok;
      }
    }
    // Wait for the inner bus at most until the next held frame is due.
    int wait_ms = static_cast<int>(std::max<int64_t>(0, (deadline_us - now) / 1000));
    {
      std::lock_guard lock(mutex_);
      if (!held_.empty()) wait_ms = std::min(wait_ms, static_cast<int>(std::max<int64_t>(0, (held_.front().first - now) / 1000)));
    }
    CanFrame f;
    const IoStatus st = inner_->receive(f, wait_ms);
    if (st != IoStatus::Ok && st != IoStatus::Timeout) return st;
    now = msgs::monotonic_us();
    if (st == IoStatus::Ok) {
      // A lost or held frame: look again at once, the bus may hold more.
      std::lock_guard lock(mutex_);
      const uint64_t n = frames_++;
      if (bus_off_) {
        ++dropped_;  // a bus-off controller receives nothing
      } else if (!f.error && hits(WireFaultKind::CanDrop, now, n)) {
        ++dropped_;
      } else {
        if (!f.error && f.len > 0 && hits(WireFaultKind::CanCorrupt, now, n)) {
          f.data[f.len - 1] ^= 0x10;  // a flipped bit the frame's CRC-8 catches
          ++corrupted_;
        }
        if (const WireFault* d = hits(WireFaultKind::CanDelay, now, n)) {
          const double delay_ms = d->rate > 0.0 ? d->rate : 50.0;
          held_.emplace_back(now + static_cast<int64_t>(delay_ms * 1000.0), f);
        } else if (held_.empty()) {
          frame = f;
          return IoStatus::Ok;
        } else {
          held_.emplace_back(now, f);  // keep the order behind frames still held
        }
      }
      continue;
    }
    if (now >= deadline_us) {
      std::lock_guard lock(mutex_);
      if (!held_.empty() && held_.front().first <= now) continue;
      return IoStatus::Timeout;
    }
  }
}

FaultyModbusLink::FaultyModbusLink(std::unique_ptr<ModbusLink> inner) : inner_(std::move(inner)) {}

std::optional<ModbusResult> FaultyModbusLink::faulted() {
  const int64_t now = msgs::monotonic_us();
  std::lock_guard lock(mutex_);
  const uint64_t n = requests_++;
  if (hits(WireFaultKind::ModbusTimeout, now, n)) return count({ModbusStatus::Timeout, 0});
  if (const WireFault* e = hits(WireFaultKind::ModbusException, now, n))
    return count({ModbusStatus::Exception, static_cast<uint8_t>(e->rate > 0.0 ? e->rate : 4.0)});
  return std::nullopt;
}

ModbusResult FaultyModbusLink::read_coils(uint16_t address, std::span<uint8_t> bits) {
  if (auto r = faulted()) return *r;
  return count(inner_->read_coils(address, bits));
}
ModbusResult FaultyModbusLink::read_discrete_inputs(uint16_t address, std::span<uint8_t> bits) {
  if (auto r = faulted()) return *r;
  return count(inner_->read_discrete_inputs(address, bits));
}
ModbusResult FaultyModbusLink::read_holding_registers(uint16_t address, std::span<uint16_t> registers) {
  if (auto r = faulted()) return *r;
  return count(inner_->read_holding_registers(address, registers));
}
ModbusResult FaultyModbusLink::read_input_registers(uint16_t address, std::span<uint16_t> registers) {
  if (auto r = faulted()) return *r;
  return count(inner_->read_input_registers(address, registers));
}
ModbusResult FaultyModbusLink::write_coils(uint16_t address, std::span<const uint8_t> bits) {
  if (auto r = faulted()) return *r;
  return count(inner_->write_coils(address, bits));
}
ModbusResult FaultyModbusLink::write_registers(uint16_t address, std::span<const uint16_t> registers) {
  if (auto r = faulted()) return *r;
  return count(inner_->write_registers(address, registers));
}

}  // namespace rise::hil::io
