#include "instructor/channel_cache.hpp"

namespace rise::instructor {

void ChannelCache::store_latest(const std::string& channel, const std::string& trainee, const std::string& kind,
                                Json::Value value) {
  std::lock_guard lock(mutex_);
  Latest& l = latest_[channel];
  l.kind = kind;
  l.trainee = trainee;
  l.value = std::move(value);
  l.version = ++version_;
  changed_.notify_all();
}

void ChannelCache::store_event(const std::string& trainee, const std::string& kind, Json::Value value) {
  std::lock_guard lock(mutex_);
  value["trainee"] = trainee;
  value["channel_kind"] = kind;
  events_.emplace_back(++version_, std::move(value));
  while (events_.size() > kRecentEvents) events_.pop_front();
  changed_.notify_all();
}

void ChannelCache::store_sound(const std::string& trainee, Json::Value value) {
  std::lock_guard lock(mutex_);
  value["trainee"] = trainee;
  sounds_.emplace_back(++version_, std::move(value));
  while (sounds_.size() > kRecentSounds) sounds_.pop_front();
  changed_.notify_all();
}

std::optional<Json::Value> ChannelCache::changes_since(uint64_t* version, std::chrono::milliseconds wait) {
  std::unique_lock lock(mutex_);
  changed_.wait_for(lock, wait, [&] { return version_ > *version || closed_; });
  if (closed_) return std::nullopt;
  Json::Value channels(Json::objectValue);
  for (const auto& [channel, l] : latest_) {
    if (l.version <= *version) continue;
    Json::Value c;
    c["trainee"] = l.trainee;
    c["kind"] = l.kind;
    c["value"] = l.value;
    channels[channel] = c;
  }
  Json::Value evs(Json::arrayValue);
  for (const auto& [v, e] : events_)
    if (v > *version) evs.append(e);
  Json::Value sounds(Json::arrayValue);
  for (const auto& [v, s] : sounds_)
    if (v > *version && *version > 0) sounds.append(s);
  Json::Value update;
  update["channels"] = channels;
  update["events"] = evs;
  update["sounds"] = sounds;
  *version = version_;
  return update;
}

std::map<std::string, Json::Value> ChannelCache::trainees() const {
  std::lock_guard lock(mutex_);
  std::map<std::string, Json::Value> by_id;
  for (const auto& [channel, l] : latest_) {
    Json::Value& t = by_id[l.trainee];
    t["id"] = l.trainee;
    t[l.kind] = l.value;
  }
  return by_id;
}

void ChannelCache::close() {
  std::lock_guard lock(mutex_);
  closed_ = true;
  changed_.notify_all();
}

}  // namespace rise::instructor
