#include "hil/io/recording_bus.hpp"

#include <stdexcept>

namespace rise::io {
namespace {
int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}
}  // namespace

RecordingBus::RecordingBus(std::unique_ptr<CanBus> bus, const std::string& path, std::string interface,
                           Stamp stamp)
    : bus_(std::move(bus)), stamp_(stamp), out_(path, std::ios::trunc), interface_(std::move(interface)),
      last_flush_(std::chrono::steady_clock::now()) {
  if (!out_) throw std::runtime_error(path + ": cannot create the CAN log");
  line_.reserve(256 + interface_.size());
}

RecordingBus::~RecordingBus() { out_.flush(); }

int64_t RecordingBus::frames_recorded() const {
  std::lock_guard lock(mutex_);
  return recorded_;
}

int64_t RecordingBus::write_errors() const {
  std::lock_guard lock(mutex_);
  return write_errors_;
}

void RecordingBus::record(const CanFrame& frame, CandumpDirection direction) {
  CanFrame stamped = frame;
  if (stamped.timestamp_us == 0 || (stamp_ == Stamp::Receive && direction == CandumpDirection::Received))
    stamped.timestamp_us = wall_us();
  std::lock_guard lock(mutex_);
  line_.clear();
  append_candump_line(line_, stamped, interface_, direction);
  line_ += '\n';
  out_.write(line_.data(), static_cast<std::streamsize>(line_.size()));
  // Flushed at least every 100 ms: a killed daemon loses at most that much.
  const auto now = std::chrono::steady_clock::now();
  if (now - last_flush_ >= std::chrono::milliseconds(100)) {
    out_.flush();
    last_flush_ = now;
  }
  if (!out_) {
    ++write_errors_;
    out_.clear();
    return;
  }
  ++recorded_;
}

IoStatus RecordingBus::send(const CanFrame& frame) {
  const IoStatus st = bus_->send(frame);
  if (st == IoStatus::Ok) record(frame, CandumpDirection::Sent);
  return st;
}

IoStatus RecordingBus::receive(CanFrame& frame, int timeout_ms) {
  const IoStatus st = bus_->receive(frame, timeout_ms);
  if (st == IoStatus::Ok) record(frame, CandumpDirection::Received);
  return st;
}

}  // namespace rise::io
