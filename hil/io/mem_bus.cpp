#include "hil/io/mem_bus.hpp"

#include <algorithm>
#include <map>
#include <mutex>
#include <vector>

#include "hil/io/posix_io.hpp"
#include "msgs/clock.hpp"

namespace rise::hil::io {

namespace detail {

// The buses of one name; the registry holds it weakly, so a name is forgotten
// when its last bus closes.
struct MemChannel {
  std::mutex mutex;
  std::vector<FrameQueue*> members;
};

}  // namespace detail

namespace {

struct Registry {
  std::mutex mutex;
  std::map<std::string, std::weak_ptr<detail::MemChannel>, std::less<>> channels;
};

Registry& registry() {
  static Registry instance;
  return instance;
}

}  // namespace

MemBus::MemBus(std::string url, const std::string& name, size_t queue_capacity)
    : url_(std::move(url)), queue_(queue_capacity) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  for (auto it = r.channels.begin(); it != r.channels.end();) {
    it = it->second.expired() ? r.channels.erase(it) : std::next(it);
  }
  auto& slot = r.channels[name];
  channel_ = slot.lock();
  if (!channel_) {
    channel_ = std::make_shared<detail::MemChannel>();
    slot = channel_;
  }
  std::lock_guard channel_lock(channel_->mutex);
  channel_->members.push_back(&queue_);
}

MemBus::~MemBus() {
  std::lock_guard lock(channel_->mutex);
  auto& members = channel_->members;
  members.erase(std::remove(members.begin(), members.end(), &queue_), members.end());
}

IoStatus MemBus::send(const CanFrame& frame) {
  if (!is_well_formed(frame)) return IoStatus::Invalid;
  CanFrame stamped = frame;
  if (stamped.timestamp_us == 0) stamped.timestamp_us = msgs::wall_us();
  std::lock_guard lock(channel_->mutex);
  for (FrameQueue* member : channel_->members) {
    if (member != &queue_) member->push(stamped);
  }
  return IoStatus::Ok;
}

IoStatus MemBus::receive(CanFrame& frame, int timeout_ms) {
  return queue_.pop(frame, timeout_ms) ? IoStatus::Ok : IoStatus::Timeout;
}

}  // namespace rise::hil::io
