#include "hil/io/recording_bus.hpp"

#include "hil/io/posix_io.hpp"
#include "msgs/clock.hpp"

namespace rise::hil::io {

RecordingBus::RecordingBus(std::unique_ptr<CanBus> bus, const std::string& path, std::string interface,
                           Stamp stamp)
    : bus_(std::move(bus)), stamp_(stamp), file_(path, "CAN log"), interface_(std::move(interface)) {
  line_.reserve(256 + interface_.size());
}

RecordingBus::~RecordingBus() = default;

void RecordingBus::record(const CanFrame& frame, CandumpDirection direction) {
  CanFrame stamped = frame;
  if (stamped.timestamp_us == 0 || (stamp_ == Stamp::Receive && direction == CandumpDirection::Received))
    stamped.timestamp_us = msgs::wall_us();
  std::lock_guard lock(mutex_);
  line_.clear();
  append_candump_line(line_, stamped, interface_, direction);
  file_.write_line(line_);
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

}  // namespace rise::hil::io
