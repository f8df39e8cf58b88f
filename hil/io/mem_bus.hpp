#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "hil/io/can_bus.hpp"
#include "hil/io/frame_queue.hpp"

namespace rise::hil::io {

namespace detail {
struct MemChannel;
}

/// mem://NAME: a bus inside this process. Every MemBus opened with the same
/// name receives the frames the others send (never its own), like nodes on
/// one wire. Each bus has its own bounded queue; a bus that does not read
/// loses frames (counted in dropped()), the senders never block.
/// Thread-safe for any number of senders and receivers.
class MemBus final : public CanBus {
 public:
  static constexpr size_t kDefaultQueueCapacity = 4096;

  MemBus(std::string url, const std::string& name, size_t queue_capacity = kDefaultQueueCapacity);
  ~MemBus() override;
  MemBus(const MemBus&) = delete;
  MemBus& operator=(const MemBus&) = delete;

  /// Delivers frame to every other bus of the same name. A frame with
  /// timestamp_us 0 is stamped with the send time. Invalid for a frame that
  /// is not well formed. No allocation: safe in the cyclic path.
  IoStatus send(const CanFrame& frame) override;
  /// Waits up to timeout_ms (0 = poll) on a condition variable.
  IoStatus receive(CanFrame& frame, int timeout_ms) override;
  IoStatus reopen() override { return IoStatus::Ok; }
  bool is_open() const override { return true; }
  const std::string& url() const override { return url_; }
  std::string last_error() const override { return {}; }

  /// Frames lost because this bus's queue was full.
  uint64_t dropped() const { return queue_.dropped(); }

 private:
  std::string url_;
  std::shared_ptr<detail::MemChannel> channel_;
  FrameQueue queue_;
};

}  // namespace rise::hil::io
