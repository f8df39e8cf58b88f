#pragma once

// A fault scenario: which faults the instructor station injects into one
// trainee's session, when, for how long, with seeded randomness, so that a
// scenario run twice with one seed against the same session replays the
// same faults at the same moments (instructor/README in ../README.md
// "Faults, scenarios and signed commands").
//
//   scenario: corridor-trouble
//   seed: 7                       # default seed; rise-instructor --seed overrides
//   faults:
//     - id: stick                 # unique; clear names it
//       kind: stuck_at            # any fault kind (README "Faults")
//       target: drive_y           # control, source, panel_state, robot side, joint, sensor
//       value: 0.4                # the kind's parameter; or value_range: [0.2, 0.6] (seeded)
//       rate: 0.0                 # the kind's second parameter
//       at: 5.0                   # trigger: seconds after the scenario starts ...
//       # on: {event: region_entered, a: t1, b: corridor}   # ... or a SimEvent (a, b optional)
//       # when: {field: speed_mps, above: 0.3}             # ... or a RobotState/PanelState condition
//       delay: 0.5                # after the trigger, plus jitter: 1.0 (seeded, uniform 0..jitter)
//       probability: 1.0          # seeded: whether it fires at all
//       duration: 3.0             # seconds; 0 / absent = until cleared
//       clear_on: {event: region_left, b: corridor}       # optional clear trigger (at/on/when)
//       auto_clear: true          # cleared when the scenario ends (default true)
//
// Condition fields: speed_mps, x_m, y_m, damage (RobotState), failsafe
// (PanelState: 1 when failsafe), sim_time_s; with `above:` or `below:`.
// Every mistake is refused with "file:line: key: what".

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace rise::instructor {

/// What starts (or clears) a fault.
struct Trigger {
  enum class Kind { None, At, Event, Condition };
  Kind kind = Kind::None;
  double at_s = 0.0;            ///< At: seconds after the scenario starts
  std::string event;            ///< Event: SimEvent kind, e.g. "region_entered"
  std::string a, b;             ///< Event: "" = any
  std::string field;            ///< Condition: speed_mps, x_m, y_m, damage, failsafe, sim_time_s
  std::optional<double> above;  ///< Condition: field > above
  std::optional<double> below;  ///< Condition: field < below
};

struct ScenarioFault {
  std::string id;
  std::string kind;
  std::string target;
  double value = 0.0;
  std::optional<std::array<double, 2>> value_range;  ///< seeded uniform value in [lo, hi]
  double rate = 0.0;
  Trigger trigger;
  double delay_s = 0.0;
  double jitter_s = 0.0;
  double probability = 1.0;
  double duration_s = 0.0;
  Trigger clear_on;
  bool auto_clear = true;
  int line = 0;  ///< where it is in the file
};

struct Scenario {
  std::string name;
  std::string file;
  uint64_t seed = 0;
  std::vector<ScenarioFault> faults;
};

/// Loads and checks a scenario file; throws std::runtime_error
/// "file:line: key: what" (unknown key or kind, no trigger, two triggers,
/// repeated id, bad number).
Scenario load_scenario(const std::string& path);
Scenario parse_scenario(const std::string& text, const std::string& file);

/// Every fault kind a scenario may name (input, wire, transport, physics, sensor).
const std::vector<std::string>& fault_kinds();

}  // namespace rise::instructor
