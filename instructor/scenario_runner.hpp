#pragma once

// Runs a Scenario against one session: fed the session's time, its
// SimEvents and its observed state, it says which faults to inject or clear
// and when. Pure (no clock, no I/O): rise-instructor feeds it from LCM with
// the wall clock, a test feeds it in process with the sim's clock; the same
// inputs and seed give the same actions. Every random draw is a function of
// (seed, fault index) only, so a fault's randomness does not depend on
// which other faults fired.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "instructor/scenario.hpp"
#include "rise_msgs/FaultCommand.hpp"

namespace rise::instructor {

struct ScenarioAction {
  double time_s = 0.0;  ///< scenario time it is due at
  bool inject = true;   ///< false: clear `id`
  std::string id;
  std::string kind;
  std::string target;
  double value = 0.0;
  double rate = 0.0;
  double duration_s = 0.0;
  uint64_t seed = 0;  ///< the fault's own seed (noise, drop, intermittent draws)
};

/// Observed state for `when:` conditions: field name → value (speed_mps,
/// x_m, y_m, damage, failsafe, sim_time_s); absent fields never match.
using Observation = std::map<std::string, double>;

class ScenarioRunner {
 public:
  /// `seed` replaces the file's seed (rise-instructor --seed).
  ScenarioRunner(Scenario scenario, uint64_t seed);

  /// Advances to scenario time t_s (non-decreasing): `at:` triggers and
  /// delayed injections that are due. Returns the actions due, in order.
  std::vector<ScenarioAction> advance(double t_s);
  /// A SimEvent of the session at t_s: `on:` triggers (inject or clear).
  std::vector<ScenarioAction> on_event(double t_s, const std::string& kind, const std::string& a,
                                       const std::string& b);
  /// The session's state at t_s: `when:` triggers fire when their condition
  /// becomes true (rising edge; true on the first observation fires too).
  std::vector<ScenarioAction> on_observation(double t_s, const Observation& observation);
  /// Clears of every injected auto_clear fault still in effect at t_s (the
  /// scenario ends); afterwards finished() is true.
  std::vector<ScenarioAction> finish(double t_s);

  /// True when every fault has fired and ended or been cleared, or will
  /// never fire (its probability draw said no).
  bool finished(double t_s) const;
  const Scenario& scenario() const { return scenario_; }
  uint64_t seed() const { return seed_; }

 private:
  enum class State { Waiting, Scheduled, Active, Done };
  struct Slot {
    State state = State::Waiting;
    double due_s = 0.0;   // Scheduled: injection time
    double end_s = 0.0;   // Active: duration end (0 = none)
    bool fires = true;
    double value = 0.0;
    double jitter_s = 0.0;
    uint64_t seed = 0;
    bool condition_was = false;
    bool clear_condition_was = false;
  };
  void trigger(std::size_t i, double t_s);
  ScenarioAction inject_action(std::size_t i, double t_s) const;
  ScenarioAction clear_action(std::size_t i, double t_s) const;
  static bool matches(const Trigger& t, const Observation& o);

  Scenario scenario_;
  uint64_t seed_;
  std::vector<Slot> slots_;
  double now_s_ = 0.0;
};

/// The FaultCommand for an action (unsigned: sign it with
/// msgs::sign right before publishing).
rise_msgs::FaultCommand to_command(const ScenarioAction& action, const std::string& trainee_id,
                                   const std::string& issuer);

}  // namespace rise::instructor
