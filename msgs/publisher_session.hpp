#pragma once

// One publisher per station id and channel. Every process that publishes a
// station's periodic messages (rise-hild and virtual panels: PanelState;
// rise-sim: RobotState; rise-trainer: TaskStatus) stamps them with its
// Publisher (msgs/lcmtypes/Publisher.lcm) and watches its own channel:
//   - at start-up it listens before its first message (probe_channel) and
//     refuses to start when another process already publishes there;
//   - while it runs, a message from another process on its channel is
//     reported once (PublisherWatch), with that process's host and pid, by
//     both sides within one period of the slower one; of two that started
//     together, the later one (yields_to) gives way.
// Two publishers on one channel would otherwise mix silently: a simulator
// driven by two consoles at once, a demo counting another demo's messages.

#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "msgs/clock.hpp"
#include "msgs/lcm_decode.hpp"
#include "rise_msgs/Publisher.hpp"

namespace rise::msgs {

/// Names this process as a publisher ("rise-hild", ...) and returns it. The
/// session id, host, pid and start time are drawn on the first call of
/// this or this_publisher() and stay the same. Thread-safe.
const rise_msgs::Publisher& init_publisher(const std::string& program);
/// This process as a publisher (program "" until init_publisher names it).
const rise_msgs::Publisher& this_publisher();

/// "rise-hild pid 4242 on lab3 (session 5f3a09c1, started 12.0 s ago)";
/// now_utime: wall clock, µs since the epoch.
std::string describe(const rise_msgs::Publisher& publisher, int64_t now_utime);

/// Of two publishers on one channel, whether `self` gives way to `other`:
/// the one that started later does; a tie goes to the lower session id.
bool yields_to(const rise_msgs::Publisher& self, const rise_msgs::Publisher& other);

/// How long after its start a process still gives way to another publisher
/// (two started together, both past their probe); later both only report.
inline constexpr int64_t kGiveWayWindowUs = 5'000'000;

/// Whether `self`, meeting `other` on its channel at now_utime, stops: it
/// yields_to() the other and is still within kGiveWayWindowUs of its start.
bool gives_way(const rise_msgs::Publisher& self, const rise_msgs::Publisher& other, int64_t now_utime);

/// The other processes seen publishing on some channels. Thread-safe.
class PublisherWatch {
 public:
  struct Other {
    std::string channel;
    rise_msgs::Publisher publisher;
    int64_t first_seen_us = 0;  ///< the caller's clock
    int64_t last_seen_us = 0;
  };

  /// `forget_after_us`: an other not heard from this long is gone (and
  /// reported again if it comes back).
  explicit PublisherWatch(int64_t own_session_id, int64_t forget_after_us = 2'000'000);

  /// Takes a received message's publisher. Returns the other process when
  /// it is new on this channel (first seen, or back after being forgotten);
  /// nothing for this process's own messages and for one already known.
  std::optional<Other> observe(const std::string& channel, const rise_msgs::Publisher& publisher, int64_t now_us);

  /// Every other process heard within forget_after_us of now_us.
  std::vector<Other> others(int64_t now_us) const;

 private:
  int64_t own_session_id_;
  int64_t forget_after_us_;
  mutable std::mutex mutex_;
  std::vector<Other> others_;
};

/// Feeds a PublisherWatch from an LCM subscription of `Message` (a type
/// with a `publisher` field) and tells `on_other` each new other process.
template <typename Message>
class PublisherListener {
 public:
  using OnOther = std::function<void(const PublisherWatch::Other&)>;
  PublisherListener(int64_t own_session_id, OnOther on_other)
      : watch_(own_session_id), on_other_(std::move(on_other)) {}
  /// Listens on `channel` of `lcm` (this object must outlive the subscription).
  void listen(lcm::LCM& lcm, const std::string& channel) {
    subscribe<&PublisherListener::on>(lcm, channel, this)->setQueueCapacity(16);
  }
  const PublisherWatch& watch() const { return watch_; }

 private:
  void on(const lcm::ReceiveBuffer*, const std::string& channel, const Message* m) {
    if (const auto other = watch_.observe(channel, m->publisher, wall_us())) on_other_(*other);
  }
  PublisherWatch watch_;
  OnOther on_other_;
};

/// A publisher found on a channel.
struct ChannelPublisher {
  std::string channel;
  rise_msgs::Publisher publisher;
};

/// Listens on `channels` (exact names) for `wait_ms` and returns the first
/// publisher of a `Message` (a type with a `publisher` field) there that is
/// not this process. Call it before the first publish and before any other
/// subscription or thread uses `lcm`.
template <typename Message>
std::optional<ChannelPublisher> probe_channels(lcm::LCM& lcm, const std::vector<std::string>& channels, int wait_ms) {
  struct Probe {
    int64_t own = this_publisher().session_id;
    std::optional<ChannelPublisher> found;
    void on(const lcm::ReceiveBuffer*, const std::string& channel, const Message* m) {
      if (!found && m->publisher.session_id != own) found = ChannelPublisher{channel, m->publisher};
    }
  } probe;
  std::vector<lcm::Subscription*> subs;
  for (const std::string& channel : channels) subs.push_back(subscribe<&Probe::on>(lcm, channel, &probe));
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(wait_ms);
  for (auto now = std::chrono::steady_clock::now(); !probe.found && now < deadline;
       now = std::chrono::steady_clock::now())
    lcm.handleTimeout(
        static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now).count()) + 1);
  for (lcm::Subscription* sub : subs) lcm.unsubscribe(sub);
  return probe.found;
}

/// probe_channels for one channel.
template <typename Message>
std::optional<rise_msgs::Publisher> probe_channel(lcm::LCM& lcm, const std::string& channel, int wait_ms) {
  const auto found = probe_channels<Message>(lcm, {channel}, wait_ms);
  return found ? std::optional<rise_msgs::Publisher>(found->publisher) : std::nullopt;
}

/// How long a publisher listens before its first message: several periods
/// of PanelState (100 Hz) and RobotState (50 Hz). rise-trainer listens
/// kSlowProbeMs, longer than TaskStatus's period (2 Hz).
inline constexpr int kProbeMs = 300;
inline constexpr int kSlowProbeMs = 700;

}  // namespace rise::msgs
