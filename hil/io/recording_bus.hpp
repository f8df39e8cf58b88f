#pragma once

// A CanBus that records every frame it receives and sends, in candump's log
// format (`candump -l`: readable by canplayer, python-can, SavvyCAN and our
// replay://), while passing everything through to the bus it wraps.

#include <chrono>
#include <fstream>
#include <memory>
#include <string>

#include "hil/io/can_bus.hpp"

namespace rise::io {

class RecordingBus final : public CanBus {
 public:
  /// Records `bus` into `path` (created or truncated) with `interface` as
  /// the log's interface name. Throws std::runtime_error if the file cannot
  /// be created.
  RecordingBus(std::unique_ptr<CanBus> bus, const std::string& path, std::string interface);
  ~RecordingBus() override;

  IoStatus send(const CanFrame& frame) override;
  IoStatus receive(CanFrame& frame, int timeout_ms) override;
  IoStatus reopen() override { return bus_->reopen(); }
  bool is_open() const override { return bus_->is_open(); }
  const std::string& url() const override { return bus_->url(); }
  std::string last_error() const override { return bus_->last_error(); }

  int64_t frames_recorded() const { return recorded_; }

 private:
  void record(const CanFrame& frame);

  std::unique_ptr<CanBus> bus_;
  std::ofstream out_;
  std::string interface_;
  int64_t recorded_ = 0;
  std::chrono::steady_clock::time_point last_flush_;
};

}  // namespace rise::io
