#pragma once

// The classroom's LCM traffic as the web console's pages see it: the latest
// message per channel (as JSON) and the recent discrete events, each stamped
// with a version, so every SSE stream sends only what changed since its last
// push. Thread-safe: the LCM thread stores, request threads read and wait.

#include <json/json.h>

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

namespace rise::instructor {

class ChannelCache {
 public:
  /// The events kept for streams that fall behind.
  static constexpr std::size_t kRecentEvents = 200;
  /// The sound cues kept: rise-sim sends each continuous cue at the
  /// RobotState rate, so a few per cue and push.
  static constexpr std::size_t kRecentSounds = 400;

  /// Replaces `channel`'s latest message (rise/<trainee>/<kind>).
  void store_latest(const std::string& channel, const std::string& trainee, const std::string& kind,
                    Json::Value value);
  /// Appends a discrete event (sim_event, task_event), tagged with
  /// "trainee" and "channel_kind".
  void store_event(const std::string& trainee, const std::string& kind, Json::Value value);

  /// Appends a SoundCue (rise/<trainee>/sound), tagged with "trainee". Every
  /// cue goes out, not only the latest: one-shots must each be played.
  void store_sound(const std::string& trainee, Json::Value value);

  /// Waits up to `wait` for anything newer than *version and returns it as
  /// {"channels": {channel: {trainee, kind, value}}, "events": [...],
  /// "sounds": [...]} (all empty when nothing came); *version becomes the
  /// newest. A new stream (*version 0) gets no sounds: those played before
  /// the page opened are over. nullopt once closed.
  std::optional<Json::Value> changes_since(uint64_t* version, std::chrono::milliseconds wait);

  /// Per trainee id: {"id": id, <kind>: latest message, ...}.
  std::map<std::string, Json::Value> trainees() const;

  /// Wakes every waiting stream; changes_since answers nullopt from now on.
  void close();

 private:
  struct Latest {
    std::string kind;
    std::string trainee;
    Json::Value value;
    uint64_t version = 0;
  };
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  bool closed_ = false;
  uint64_t version_ = 0;
  std::map<std::string, Latest> latest_;
  std::deque<std::pair<uint64_t, Json::Value>> events_;
  std::deque<std::pair<uint64_t, Json::Value>> sounds_;
};

}  // namespace rise::instructor
