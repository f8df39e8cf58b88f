#pragma once

// Each trainee station's link as the instructor sees it across a LAN: when
// it was last heard (on this host's steady clock, so no other host's clock
// matters), the offset of each of its hosts' clocks from this host's as
// measured by probe and echo (msgs/clock_offset.hpp; a station is usually one
// host, but its programs may run on several), and how old its newest state
// was when it arrived, judged in this host's clock: arrival − (utime −
// the offset of the host that sent it).
//   live  heard within lost_after, and its newest state no older (or newer)
//         than lost_after on arrival;
//   stale heard, but its stamps are that far off: a clock not yet measured,
//         or messages that arrive late;
//   lost  nothing heard for lost_after (a cut cable, a stopped station).
// Thread-safe: the LCM thread feeds it, request threads read it.

#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "msgs/clock_offset.hpp"

namespace rise::instructor {

struct TraineeLink {
  std::string id;
  std::string state;                    ///< "live", "stale", "lost"
  int64_t heard_ago_us = 0;             ///< since the newest message arrived (this host's steady clock)
  int64_t arrival_age_us = 0;           ///< the newest state's age on arrival, offset applied
  std::optional<msgs::ClockSample> clock;  ///< the station's clock − this host's; none until an echo came
  std::string clock_host;               ///< the host whose clock that is (the newest state's, when it answers)
};

class TraineeLinks {
 public:
  /// `lost_after_us`: the silence after which a station is lost (and the
  /// largest age on arrival of a live one); `filter_window`: echoes kept.
  explicit TraineeLinks(int64_t lost_after_us = 500'000, std::size_t filter_window = 8);

  /// A state (PanelState, RobotState, TaskStatus) of `trainee` from a
  /// process on `host`, stamped `utime` (that host's clock), arrived at
  /// now_wall_us / now_steady_us (ours).
  void heard(const std::string& trainee, const std::string& host, int64_t utime, int64_t now_wall_us,
             int64_t now_steady_us);
  /// An echo of one of our probes arrived at now_wall_us (t4).
  void on_echo(const std::string& trainee, const rise_msgs::ClockEcho& echo, int64_t now_wall_us);

  /// The trainees heard so far (the ones to probe).
  std::vector<std::string> trainees() const;
  /// The trainee's clock − ours, once measured: of its hosts' the least
  /// delayed (the clock its rise-hild and rise-sim judge commands by).
  std::optional<int64_t> offset_us(const std::string& trainee) const;
  /// One trainee's link at now_steady_us; nullopt for one never heard.
  std::optional<TraineeLink> link(const std::string& trainee, int64_t now_steady_us) const;
  std::vector<TraineeLink> links(int64_t now_steady_us) const;

  int64_t lost_after_us() const { return lost_after_us_; }

 private:
  struct Entry {
    int64_t heard_steady_us = 0;
    int64_t arrival_wall_us = 0;
    int64_t utime = 0;
    std::string host;  // of the newest state
    std::map<std::string, msgs::ClockOffsetFilter> clocks;  // per host that answered
  };
  /// The least delayed sample of `e`'s hosts, with its host.
  static std::optional<std::pair<std::string, msgs::ClockSample>> best_clock(const Entry& e);
  TraineeLink describe(const std::string& id, const Entry& e, int64_t now_steady_us) const;

  int64_t lost_after_us_;
  std::size_t filter_window_;
  mutable std::mutex mutex_;
  std::map<std::string, Entry> entries_;
};

}  // namespace rise::instructor
