#include "instructor/trainee_links.hpp"

#include <cstdlib>

namespace rise::instructor {

TraineeLinks::TraineeLinks(int64_t lost_after_us, std::size_t filter_window)
    : lost_after_us_(lost_after_us), filter_window_(filter_window) {}

void TraineeLinks::heard(const std::string& trainee, int64_t utime, int64_t now_wall_us, int64_t now_steady_us) {
  std::lock_guard lock(mutex_);
  auto [it, added] = entries_.try_emplace(trainee, Entry{0, 0, 0, msgs::ClockOffsetFilter(filter_window_), {}});
  Entry& e = it->second;
  e.heard_steady_us = now_steady_us;
  e.arrival_wall_us = now_wall_us;
  e.utime = utime;
}

void TraineeLinks::on_echo(const std::string& trainee, const rise_msgs::ClockEcho& echo, int64_t now_wall_us) {
  std::lock_guard lock(mutex_);
  auto [it, added] = entries_.try_emplace(trainee, Entry{0, 0, 0, msgs::ClockOffsetFilter(filter_window_), {}});
  Entry& e = it->second;
  const msgs::ClockSample s = msgs::clock_sample(echo.probe_utime, echo.receive_utime, echo.utime, now_wall_us);
  e.filter.add(s);
  e.hosts[s.at_us] = echo.publisher.host;
  // Only the samples the filter still holds can be chosen.
  while (e.hosts.size() > 4 * filter_window_) e.hosts.erase(e.hosts.begin());
}

std::vector<std::string> TraineeLinks::trainees() const {
  std::lock_guard lock(mutex_);
  std::vector<std::string> out;
  for (const auto& [id, e] : entries_) out.push_back(id);
  return out;
}

std::optional<int64_t> TraineeLinks::offset_us(const std::string& trainee) const {
  std::lock_guard lock(mutex_);
  const auto it = entries_.find(trainee);
  if (it == entries_.end()) return std::nullopt;
  const auto best = it->second.filter.best();
  if (!best) return std::nullopt;
  return best->offset_us;
}

TraineeLink TraineeLinks::describe(const std::string& id, const Entry& e, int64_t now_steady_us) const {
  TraineeLink l;
  l.id = id;
  l.clock = e.filter.best();
  if (l.clock) {
    const auto host = e.hosts.find(l.clock->at_us);
    if (host != e.hosts.end()) l.clock_host = host->second;
  }
  l.heard_ago_us = now_steady_us - e.heard_steady_us;
  l.arrival_age_us = e.arrival_wall_us - (e.utime - (l.clock ? l.clock->offset_us : 0));
  if (e.heard_steady_us == 0 || l.heard_ago_us > lost_after_us_) l.state = "lost";
  else if (std::llabs(l.arrival_age_us) > lost_after_us_) l.state = "stale";
  else l.state = "live";
  return l;
}

std::optional<TraineeLink> TraineeLinks::link(const std::string& trainee, int64_t now_steady_us) const {
  std::lock_guard lock(mutex_);
  const auto it = entries_.find(trainee);
  if (it == entries_.end() || it->second.heard_steady_us == 0) return std::nullopt;
  return describe(it->first, it->second, now_steady_us);
}

std::vector<TraineeLink> TraineeLinks::links(int64_t now_steady_us) const {
  std::lock_guard lock(mutex_);
  std::vector<TraineeLink> out;
  for (const auto& [id, e] : entries_)
    if (e.heard_steady_us != 0) out.push_back(describe(id, e, now_steady_us));
  return out;
}

}  // namespace rise::instructor
