#pragma once

// A scripted console for demos and tests: plays a panel timeline
// (panels/scripts/*.txt) against a panel definition on the simulator's
// clock — times are seconds of sim time since the task started — and gives
// what the bridge would publish: the controls after the definition's
// deadband, invert and scale, motion controls zeroed while the dead-man is
// released, failsafe while the e-stop is pressed. Not the real chain (no
// firmware frames, no rise-hild): `rise demo` covers that; this is the
// virtual panel of DESIGN.md driven by a script.

#include <cstdint>
#include <string>
#include <vector>

#include "panels/panel_definition.hpp"
#include "panels/timeline.hpp"
#include "rise_msgs/PanelState.hpp"
#include "sim/simulation.hpp"
#include "sim/training/task_executor.hpp"

namespace rise::trainer {

class ScriptedConsole {
 public:
  /// Throws std::runtime_error "file:line: ..." for a bad definition or script.
  ScriptedConsole(const std::string& panel_file, const std::string& script_file);
  /// Applies the script's events up to sim time t_s (monotonic).
  void advance(double t_s);
  /// The panel as rise-sim's control mapping reads it (fresh, as if just received).
  sim::ControlInput input() const;
  rise_msgs::PanelState panel_state(const std::string& trainee_id, int64_t seq, int64_t utime) const;
  /// The script went @silent (no PanelState should go out) or reached @end.
  bool silent() const { return silent_; }
  bool ended() const { return ended_; }
  double end_time_s() const { return timeline_.end_time_s(); }

 private:
  float axis_value(std::size_t control) const;
  bool deadman_held() const;

  panels::PanelDefinition definition_;
  panels::Timeline timeline_;
  std::size_t next_ = 0;
  std::vector<float> axes_;
  std::vector<bool> buttons_;
  std::vector<uint8_t> switches_;
  bool silent_ = false;
  bool ended_ = false;
};

/// Runs `task` in-process, without LCM: a fresh Simulation of its robot,
/// world and start pose, `console` (may be null: no panel) played on sim
/// time, the executor fed every step's events and a state every 20 ms (as
/// rise-sim publishes them at 50 Hz) until the task ends.
sim::training::TaskResult play_task(const sim::training::TaskDescription& task, ScriptedConsole* console);

}  // namespace rise::trainer
