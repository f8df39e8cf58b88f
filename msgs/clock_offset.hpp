#pragma once

// Clock offsets between hosts, measured as NTP measures them (RFC 5905,
// section 8), over LCM. A prober (the instructor) sends a ClockProbe with its
// wall clock t1 on rise/<id>/clock_probe; each station process that answers
// (ClockEchoResponder: rise-hild, rise-sim) notes its clock t2 on receipt and
// t3 on sending a ClockEcho on rise/<id>/clock_echo; the prober notes t4 on
// receipt. Then
//   offset = ((t2 − t1) + (t3 − t4)) / 2   the station's clock − the prober's
//   delay  = (t4 − t1) − (t3 − t2)         the round trip on the wire
// Worked example: t1 = 1000, t2 = 6'001'200, t3 = 6'001'250, t4 = 1500 →
// offset = (6'000'200 + 5'999'750) / 2 = 5'999'975 µs, delay = 450 µs.
// The offset is exact when both legs take as long; otherwise it is off by
// half their difference, at most delay / 2. ClockOffsetFilter keeps the last
// samples and takes the one with the least delay (NTP's clock filter): the
// least delayed is the least biased.
//
// A timestamp another host stamped (`utime`, its wall clock) is then judged
// against this host's clock as utime − offset. The instructor does so for
// the trainees' states and stamps its signed commands in each receiver's
// clock (utime = own clock + offset), so that a station whose clock is off
// by seconds still finds them inside its --command-window.

#include <lcm/lcm-cpp.hpp>

#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>

#include "rise_msgs/ClockEcho.hpp"
#include "rise_msgs/ClockProbe.hpp"
#include "rise_msgs/Publisher.hpp"

namespace rise::msgs {

/// One probe/echo exchange, µs.
struct ClockSample {
  int64_t offset_us = 0;  ///< the station's clock − the prober's
  int64_t delay_us = 0;   ///< round trip, without the station's own time
  int64_t at_us = 0;      ///< t4, the prober's clock
};

/// The sample of one exchange from its four timestamps (formulas above).
ClockSample clock_sample(int64_t t1, int64_t t2, int64_t t3, int64_t t4);

/// The best of the last `window` samples of one peer: the least delayed.
/// Not thread-safe; no allocation once the window is full.
class ClockOffsetFilter {
 public:
  explicit ClockOffsetFilter(std::size_t window = 8);
  void add(const ClockSample& sample);
  /// The least delayed sample kept; nullopt before the first.
  std::optional<ClockSample> best() const;

 private:
  std::size_t window_;
  std::deque<ClockSample> samples_;
};

/// Measures a station's offset from a short-lived program (rise-instructor
/// inject, scenario, task): `probes` probes `period_ms` apart on
/// `trainee_id`'s clock_probe channel, the echoes taken until `period_ms`
/// after the last; the least delayed sample, or nullopt when no station
/// process answered. Blocks, handling `lcm` (other subscriptions' handlers
/// run too); not for the cyclic path.
std::optional<ClockSample> measure_clock_offset(lcm::LCM& lcm, const std::string& trainee_id, int probes = 3,
                                                int period_ms = 40);

/// Answers every ClockProbe on a station's clock_probe channel with a
/// ClockEcho on its clock_echo channel, from the LCM thread that handles it.
/// Keep it alive as long as the LCM object handles messages.
class ClockEchoResponder {
 public:
  ClockEchoResponder(lcm::LCM& lcm, const rise_msgs::Publisher& self) : lcm_(lcm), self_(self) {}
  /// Subscribes to `trainee_id`'s probes (call once per station id served).
  void listen(const std::string& trainee_id);
  int64_t answered() const { return answered_; }

 private:
  struct Station {
    ClockEchoResponder* responder;
    std::string echo_channel;
    void on(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::ClockProbe* probe);
  };
  lcm::LCM& lcm_;
  rise_msgs::Publisher self_;
  std::deque<Station> stations_;  // stable addresses for the subscriptions
  int64_t answered_ = 0;
};

}  // namespace rise::msgs
