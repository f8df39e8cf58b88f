#include "hil/io/recording_bus.hpp"

#include <stdexcept>

#include "hil/io/candump_log.hpp"

namespace rise::io {
namespace {
int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}
}  // namespace

RecordingBus::RecordingBus(std::unique_ptr<CanBus> bus, const std::string& path, std::string interface)
    : bus_(std::move(bus)), out_(path, std::ios::trunc), interface_(std::move(interface)),
      last_flush_(std::chrono::steady_clock::now()) {
  if (!out_) throw std::runtime_error(path + ": cannot create the CAN log");
}

RecordingBus::~RecordingBus() { out_.flush(); }

void RecordingBus::record(const CanFrame& frame) {
  CanFrame stamped = frame;
  if (stamped.timestamp_us == 0) stamped.timestamp_us = wall_us();
  out_ << format_candump_line(stamped, interface_) << '\n';
  ++recorded_;
  // Flushed at least every 100 ms: a killed daemon loses at most that much.
  const auto now = std::chrono::steady_clock::now();
  if (now - last_flush_ >= std::chrono::milliseconds(100)) {
    out_.flush();
    last_flush_ = now;
  }
}

IoStatus RecordingBus::send(const CanFrame& frame) {
  const IoStatus st = bus_->send(frame);
  if (st == IoStatus::Ok) record(frame);
  return st;
}

IoStatus RecordingBus::receive(CanFrame& frame, int timeout_ms) {
  const IoStatus st = bus_->receive(frame, timeout_ms);
  if (st == IoStatus::Ok) record(frame);
  return st;
}

}  // namespace rise::io
