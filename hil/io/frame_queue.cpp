#include "hil/io/frame_queue.hpp"

#include <chrono>

namespace rise::hil::io {

FrameQueue::FrameQueue(size_t capacity) : ring_(capacity == 0 ? 1 : capacity) {}

bool FrameQueue::push(const CanFrame& frame) {
  {
    std::lock_guard lock(mutex_);
    if (count_ == ring_.size()) {
      ++dropped_;
      return false;
    }
    ring_[(head_ + count_) % ring_.size()] = frame;
    ++count_;
  }
  ready_.notify_one();
  return true;
}

bool FrameQueue::pop(CanFrame& frame, int timeout_ms) {
  std::unique_lock lock(mutex_);
  if (count_ == 0 && timeout_ms > 0) {
    ready_.wait_for(lock, std::chrono::milliseconds(timeout_ms), [this] { return count_ > 0; });
  }
  if (count_ == 0) return false;
  frame = ring_[head_];
  head_ = (head_ + 1) % ring_.size();
  --count_;
  return true;
}

uint64_t FrameQueue::dropped() const {
  std::lock_guard lock(mutex_);
  return dropped_;
}

size_t FrameQueue::size() const {
  std::lock_guard lock(mutex_);
  return count_;
}

}  // namespace rise::hil::io
