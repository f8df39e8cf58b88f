#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <vector>

#include "hil/io/can_frame.hpp"

namespace rise::hil::io {

/// Bounded multi-producer multi-consumer queue of frames: storage is
/// allocated once, a full queue drops the new frame and counts it (a CAN
/// receiver that falls behind loses frames; it does not stall the bus).
class FrameQueue {
 public:
  explicit FrameQueue(size_t capacity);

  /// Appends frame; false when the queue was full (counted in dropped()).
  /// Thread-safe, no allocation: safe in the cyclic path.
  bool push(const CanFrame& frame);

  /// Waits up to timeout_ms (0 or less = do not wait) for the oldest frame.
  /// False on timeout. Thread-safe, no allocation.
  bool pop(CanFrame& frame, int timeout_ms);

  /// Frames dropped because the queue was full.
  uint64_t dropped() const;
  size_t size() const;
  size_t capacity() const { return ring_.size(); }

 private:
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::vector<CanFrame> ring_;
  size_t head_ = 0;
  size_t count_ = 0;
  uint64_t dropped_ = 0;
};

}  // namespace rise::hil::io
