#include "instructor/trainee_links.hpp"

#include <cstdlib>

namespace rise::instructor {

TraineeLinks::TraineeLinks(int64_t lost_after_us, std::size_t filter_window)
    : lost_after_us_(lost_after_us), filter_window_(filter_window) {}

void TraineeLinks::heard(const std::string& trainee, const std::string& host, int64_t utime, int64_t now_wall_us,
                         int64_t now_steady_us) {
  std::lock_guard lock(mutex_);
  Entry& e = entries_[trainee];
  e.heard_steady_us = now_steady_us;
  e.arrival_wall_us = now_wall_us;
  e.utime = utime;
  e.host = host;
}

void TraineeLinks::on_echo(const std::string& trainee, const rise_msgs::ClockEcho& echo, int64_t now_wall_us) {
  std::lock_guard lock(mutex_);
  auto& clocks = entries_[trainee].clocks;
  const auto [it, added] = clocks.try_emplace(echo.publisher.host, filter_window_);
  it->second.add(msgs::clock_sample(echo.probe_utime, echo.receive_utime, echo.utime, now_wall_us));
}

std::vector<std::string> TraineeLinks::trainees() const {
  std::lock_guard lock(mutex_);
  std::vector<std::string> out;
  for (const auto& [id, e] : entries_) out.push_back(id);
  return out;
}

std::optional<std::pair<std::string, msgs::ClockSample>> TraineeLinks::best_clock(const Entry& e) {
  std::optional<std::pair<std::string, msgs::ClockSample>> best;
  for (const auto& [host, filter] : e.clocks) {
    const auto s = filter.best();
    if (s && (!best || s->delay_us < best->second.delay_us)) best = std::make_pair(host, *s);
  }
  return best;
}

std::optional<int64_t> TraineeLinks::offset_us(const std::string& trainee) const {
  std::lock_guard lock(mutex_);
  const auto it = entries_.find(trainee);
  if (it == entries_.end()) return std::nullopt;
  const auto best = best_clock(it->second);
  if (!best) return std::nullopt;
  return best->second.offset_us;
}

TraineeLink TraineeLinks::describe(const std::string& id, const Entry& e, int64_t now_steady_us) const {
  TraineeLink l;
  l.id = id;
  // The clock of the host that sent the newest state; else the station's best.
  const auto own = e.clocks.find(e.host);
  if (own != e.clocks.end() && own->second.best()) {
    l.clock = own->second.best();
    l.clock_host = e.host;
  } else if (const auto best = best_clock(e)) {
    l.clock = best->second;
    l.clock_host = best->first;
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
