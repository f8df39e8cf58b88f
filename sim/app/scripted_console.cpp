#include "sim/app/scripted_console.hpp"

#include <algorithm>
#include <cmath>

#include "msgs/failsafe.hpp"

namespace rise::trainer {

using panels::ControlKind;
using panels::ControlRole;

ScriptedConsole::ScriptedConsole(const std::string& panel_file, const std::string& script_file)
    : definition_(panels::load_panel_definition(panel_file)),
      timeline_(panels::load_timeline(script_file, definition_)) {
  // The firmware's startup state: sticks centred, buttons up, switches at position 0.
  axes_.assign(definition_.controls.size(), 0.0f);
  buttons_.assign(definition_.controls.size(), false);
  switches_.assign(definition_.controls.size(), 0);
}

void ScriptedConsole::advance(double t_s) {
  using Kind = panels::TimelineEvent::Kind;
  while (next_ < timeline_.events.size() && timeline_.events[next_].time_s <= t_s + 1e-9) {
    const auto& e = timeline_.events[next_++];
    switch (e.kind) {
      case Kind::Set:
        axes_[e.control] = e.axis;
        buttons_[e.control] = e.pressed;
        switches_[e.control] = e.position;
        break;
      case Kind::Silent: silent_ = true; break;
      case Kind::Resume: silent_ = false; break;
      case Kind::End: ended_ = true; break;
      default: break;  // frame-level faults have no meaning without frames
    }
  }
}

bool ScriptedConsole::deadman_held() const {
  for (std::size_t i = 0; i < definition_.controls.size(); ++i)
    if (definition_.controls[i].role == ControlRole::Deadman) return buttons_[i];
  return true;
}

float ScriptedConsole::axis_value(std::size_t i) const {
  const auto& c = definition_.controls[i];
  float x = c.invert ? -axes_[i] : axes_[i];
  const float d = c.deadband;
  const float m = std::abs(x) <= d ? 0.0f : (std::abs(x) - d) / (1.0f - d);
  x = std::copysign(m, x);
  return std::clamp(c.scale * x, -1.0f, 1.0f);
}

sim::ControlInput ScriptedConsole::input() const {
  sim::ControlInput in;
  const bool held = deadman_held();
  bool estop = false;
  for (std::size_t i = 0; i < definition_.controls.size(); ++i) {
    const auto& c = definition_.controls[i];
    const bool zero = c.motion && !held;
    switch (c.kind) {
      case ControlKind::Axis: in.axes[c.name] = zero ? c.safe_axis : axis_value(i); break;
      case ControlKind::Button:
        in.buttons[c.name] = zero ? c.safe_button : buttons_[i];
        estop = estop || (c.role == ControlRole::Estop && buttons_[i]);
        break;
      case ControlKind::Switch:
        in.switches[c.name] = switches_[i];
        in.switch_labels[c.name] = switches_[i] < c.positions.size() ? c.positions[switches_[i]] : "";
        break;
    }
  }
  in.deadman = held;
  in.failsafe = estop;
  in.fresh = !silent_;
  return in;
}

rise_msgs::PanelState ScriptedConsole::panel_state(const std::string& trainee_id, int64_t seq, int64_t utime) const {
  const auto in = input();
  rise_msgs::PanelState m;
  m.utime = utime;
  m.panel_id = definition_.name;
  m.trainee_id = trainee_id;
  m.seq = seq;
  m.failsafe = in.failsafe;
  m.failsafe_causes = in.failsafe ? static_cast<int32_t>(msgs::FailsafeCause::Estop) : 0;
  m.failsafe_reason = in.failsafe ? "e-stop pressed (scripted console)" : "";
  m.deadman = in.deadman;
  for (const auto& [name, v] : in.axes) m.axes.push_back(rise_msgs::PanelAxis{name, v});
  for (const auto& [name, v] : in.buttons) m.buttons.push_back(rise_msgs::PanelButton{name, v});
  for (const auto& [name, v] : in.switches)
    m.switches.push_back(rise_msgs::PanelSwitch{name, static_cast<int8_t>(v), in.switch_labels.at(name)});
  m.num_axes = static_cast<int16_t>(m.axes.size());
  m.num_buttons = static_cast<int16_t>(m.buttons.size());
  m.num_switches = static_cast<int16_t>(m.switches.size());
  m.num_sources = 0;
  m.num_faults = 0;
  return m;
}

sim::training::TaskResult play_task(const sim::training::TaskDescription& task, ScriptedConsole* console) {
  sim::RobotSpec spec;
  spec.description = sim::load_robot_description(task.robot_file);
  spec.id = spec.description.name;
  spec.start = task.start;
  const auto world = sim::load_world_description(task.world_file);
  sim::Simulation simulation({spec}, world);
  sim::training::TaskExecutor executor(task, world, spec.id);
  executor.on_state(sim::training::sample_of(simulation, world));
  for (int64_t step = 1; !executor.finished(); ++step) {
    if (console) {
      console->advance(simulation.time_s());
      simulation.set_input(console->input());
    }
    simulation.step();
    for (const auto& e : simulation.take_events()) executor.on_sim_event(sim::training::from_sim(e));
    if (step % 20 == 0) executor.on_state(sim::training::sample_of(simulation, world));
  }
  return executor.result();
}

}  // namespace rise::trainer
