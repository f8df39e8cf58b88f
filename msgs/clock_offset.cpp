#include "msgs/clock_offset.hpp"

#include <poll.h>

#include <algorithm>

#include "msgs/channels.hpp"
#include "msgs/clock.hpp"
#include "msgs/lcm_decode.hpp"
#include "msgs/publisher_session.hpp"

namespace rise::msgs {

ClockSample clock_sample(int64_t t1, int64_t t2, int64_t t3, int64_t t4) {
  // Halved separately: the sums of two epoch-sized times cannot overflow.
  return {(t2 - t1) / 2 + (t3 - t4) / 2, (t4 - t1) - (t3 - t2), t4};
}

ClockOffsetFilter::ClockOffsetFilter(std::size_t window) : window_(std::max<std::size_t>(window, 1)) {}

void ClockOffsetFilter::add(const ClockSample& sample) {
  if (samples_.size() == window_) samples_.pop_front();
  samples_.push_back(sample);
}

std::optional<ClockSample> ClockOffsetFilter::best() const {
  if (samples_.empty()) return std::nullopt;
  return *std::min_element(samples_.begin(), samples_.end(),
                           [](const ClockSample& a, const ClockSample& b) { return a.delay_us < b.delay_us; });
}

namespace {

// The echoes of one prober's probes, as samples.
struct EchoCollector {
  int64_t session = 0;
  ClockOffsetFilter filter{64};
  void on(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::ClockEcho* e) {
    const int64_t t4 = wall_us();
    if (e->prober_session == session) filter.add(clock_sample(e->probe_utime, e->receive_utime, e->utime, t4));
  }
};

}  // namespace

std::optional<ClockSample> measure_clock_offset(lcm::LCM& lcm, const std::string& trainee_id, int probes,
                                                int period_ms) {
  EchoCollector collector;
  collector.session = this_publisher().session_id;
  lcm::Subscription* sub = subscribe<&EchoCollector::on>(lcm, clock_echo_channel(trainee_id), &collector);
  sub->setQueueCapacity(64);
  const int64_t period_us = int64_t{period_ms} * 1000;
  int64_t next_us = monotonic_us();
  const int64_t end_us = next_us + probes * period_us;
  for (int sent = 0; monotonic_us() < end_us || sent < probes;) {
    if (sent < probes && monotonic_us() >= next_us) {
      rise_msgs::ClockProbe probe;
      probe.prober_session = collector.session;
      probe.seq = ++sent;
      probe.utime = wall_us();
      lcm.publish(clock_probe_channel(trainee_id), &probe);
      next_us += period_us;
    }
    pollfd pfd{lcm.getFileno(), POLLIN, 0};
    if (::poll(&pfd, 1, 5) > 0) lcm.handle();
  }
  lcm.unsubscribe(sub);
  return collector.filter.best();
}

void ClockEchoResponder::listen(const std::string& trainee_id) {
  stations_.push_back({this, clock_echo_channel(trainee_id)});
  subscribe<&Station::on>(lcm_, clock_probe_channel(trainee_id), &stations_.back())->setQueueCapacity(16);
}

void ClockEchoResponder::Station::on(const lcm::ReceiveBuffer*, const std::string&,
                                     const rise_msgs::ClockProbe* probe) {
  rise_msgs::ClockEcho echo;
  echo.receive_utime = wall_us();
  echo.probe_utime = probe->utime;
  echo.prober_session = probe->prober_session;
  echo.seq = probe->seq;
  echo.publisher = responder->self_;
  echo.utime = wall_us();
  responder->lcm_.publish(echo_channel, &echo);
  ++responder->answered_;
}

}  // namespace rise::msgs
