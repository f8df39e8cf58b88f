#include "msgs/publisher_session.hpp"
#include "msgs/clock.hpp"

#include <unistd.h>

#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <random>

namespace rise::msgs {
namespace {

std::mutex g_mutex;

rise_msgs::Publisher& publisher_locked() {
  static rise_msgs::Publisher p = [] {
    rise_msgs::Publisher q{};
    std::random_device random;  // /dev/urandom (getrandom) on Linux
    while (q.session_id == 0)
      q.session_id = static_cast<int64_t>((static_cast<uint64_t>(random()) << 32) | random()) & INT64_MAX;
    char host[256] = {};
    if (::gethostname(host, sizeof host - 1) != 0) std::snprintf(host, sizeof host, "unknown");
    q.host = host;
    q.pid = static_cast<int32_t>(::getpid());
    q.started_utime = wall_us();
    return q;
  }();
  return p;
}
}  // namespace

const rise_msgs::Publisher& init_publisher(const std::string& program) {
  std::lock_guard lock(g_mutex);
  rise_msgs::Publisher& p = publisher_locked();
  p.program = program;
  return p;
}

const rise_msgs::Publisher& this_publisher() {
  std::lock_guard lock(g_mutex);
  return publisher_locked();
}

std::string describe(const rise_msgs::Publisher& p, int64_t now_utime) {
  char buf[128];
  std::snprintf(buf, sizeof buf, " pid %d on %s (session %08" PRIx64 ", started %.1f s ago)", p.pid,
                p.host.empty() ? "?" : p.host.c_str(), static_cast<uint64_t>(p.session_id) >> 32,
                (static_cast<double>(now_utime) - static_cast<double>(p.started_utime)) * 1e-6);  // started_utime is anyone's
  return (p.program.empty() ? std::string("a process") : p.program) + buf;
}

bool yields_to(const rise_msgs::Publisher& self, const rise_msgs::Publisher& other) {
  if (self.started_utime != other.started_utime) return self.started_utime > other.started_utime;
  return self.session_id > other.session_id;
}

bool gives_way(const rise_msgs::Publisher& self, const rise_msgs::Publisher& other, int64_t now_utime) {
  return yields_to(self, other) && now_utime - self.started_utime < kGiveWayWindowUs;
}

PublisherWatch::PublisherWatch(int64_t own_session_id, int64_t forget_after_us)
    : own_session_id_(own_session_id), forget_after_us_(forget_after_us) {}

std::optional<PublisherWatch::Other> PublisherWatch::observe(const std::string& channel,
                                                             const rise_msgs::Publisher& publisher, int64_t now_us) {
  if (publisher.session_id == own_session_id_) return std::nullopt;
  std::lock_guard lock(mutex_);
  for (Other& o : others_) {
    if (o.channel != channel || o.publisher.session_id != publisher.session_id) continue;
    const bool was_gone = now_us - o.last_seen_us > forget_after_us_;
    o.last_seen_us = now_us;
    if (!was_gone) return std::nullopt;
    o.first_seen_us = now_us;
    return o;
  }
  others_.push_back(Other{channel, publisher, now_us, now_us});
  return others_.back();
}

std::vector<PublisherWatch::Other> PublisherWatch::others(int64_t now_us) const {
  std::lock_guard lock(mutex_);
  std::vector<Other> out;
  for (const Other& o : others_)
    if (now_us - o.last_seen_us <= forget_after_us_) out.push_back(o);
  return out;
}

}  // namespace rise::msgs
