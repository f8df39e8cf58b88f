// Panel input to commands: the robot file's control mapping (drive, arm,
// gripper) and what a step applies to the motors; the horn's button cues.

#include <ode/ode.h>

#include <algorithm>
#include <cmath>

#include "sim/simulation_impl.hpp"

namespace rise::sim {
namespace {

using Enable = std::optional<std::pair<std::string, std::string>>;

bool allowed(const Enable& enable, const ControlMapping& m, const ControlInput& in, std::string& reason) {
  if (!in.fresh) { reason = "no panel state"; return false; }
  if (in.failsafe) { reason = "panel failsafe"; return false; }
  if (m.estop_button) {
    const auto it = in.buttons.find(*m.estop_button);
    if (it == in.buttons.end() || it->second) { reason = "e-stop"; return false; }
  }
  if (!in.deadman) { reason = "dead-man released"; return false; }
  if (enable) {
    const auto it = in.switch_labels.find(enable->first);
    if (it == in.switch_labels.end() || it->second != enable->second) {
      reason = enable->first + " not " + enable->second;
      return false;
    }
  }
  return true;
}

double axis_value(const AxisMapping& a, const ControlInput& in) {
  const auto it = in.axes.find(a.axis);
  if (it == in.axes.end()) return 0.0;
  const double v = std::clamp(static_cast<double>(it->second), -1.0, 1.0);
  return (a.invert ? -v : v) * a.max;
}

bool pressed(const ControlInput& in, const std::string& button) {
  const auto it = in.buttons.find(button);
  return it != in.buttons.end() && it->second;
}

}  // namespace

DriveCommand map_controls(const ControlMapping& mapping, const ControlInput& input) {
  DriveCommand c;
  if (!allowed(mapping.enable, mapping, input, c.stop_reason)) return c;
  double scale = 1.0;
  if (mapping.speed_scale) {
    const auto it = input.switches.find(mapping.speed_scale->first);
    const auto& values = mapping.speed_scale->second;
    if (it == input.switches.end() || it->second < 0 || static_cast<std::size_t>(it->second) >= values.size()) {
      c.stop_reason = mapping.speed_scale->first + " position unknown";
      return c;
    }
    scale = values[static_cast<std::size_t>(it->second)];
  }
  c.linear_mps = scale * axis_value(mapping.linear, input);
  c.angular_radps = scale * axis_value(mapping.angular, input);
  c.enabled = true;
  return c;
}

JointCommand map_joint_controls(const ControlMapping& mapping, const ControlInput& input) {
  JointCommand c;
  c.values.assign(mapping.joints.size(), 0.0);
  c.enabled.assign(mapping.joints.size(), false);
  double scale = 1.0;
  if (mapping.speed_scale) {
    const auto it = input.switches.find(mapping.speed_scale->first);
    const auto& values = mapping.speed_scale->second;
    // An unknown position stops the velocity joints, as it stops driving.
    scale = it == input.switches.end() || it->second < 0 || static_cast<std::size_t>(it->second) >= values.size()
                ? 0.0
                : values[static_cast<std::size_t>(it->second)];
  }
  for (std::size_t i = 0; i < mapping.joints.size(); ++i) {
    const JointControl& j = mapping.joints[i];
    std::string reason;
    if (!allowed(j.enable ? j.enable : mapping.enable, mapping, input, reason)) continue;
    double v = j.axis.axis.empty() ? 0.0 : axis_value(j.axis, input);
    if (j.mix) v += axis_value(*j.mix, input);
    if (j.buttons && pressed(input, j.buttons->first) != pressed(input, j.buttons->second))
      v = pressed(input, j.buttons->first) ? j.axis.max : -j.axis.max;
    c.values[i] = j.mode == JointControlMode::Velocity ? v * scale : v;
    c.enabled[i] = true;
  }
  return c;
}

ArmCommand map_arm_controls(const ControlMapping& mapping, const ControlInput& input) {
  ArmCommand c;
  if (!mapping.arm) {
    c.stop_reason = "no arm";
    return c;
  }
  const ArmMapping& arm = *mapping.arm;
  c.joint_radps.assign(arm.joints.size(), 0.0);
  if (!allowed(arm.enable, mapping, input, c.stop_reason)) return c;
  for (std::size_t i = 0; i < arm.joints.size(); ++i) c.joint_radps[i] = axis_value(arm.joints[i].axis, input);
  const bool open = pressed(input, arm.open_button);
  const bool close = pressed(input, arm.close_button);
  if (open != close) c.gripper_mps = open ? arm.gripper_speed_mps : -arm.gripper_speed_mps;
  c.enabled = true;
  return c;
}

void Simulation::Impl::apply_command(Robot& r) {
  r.command = map_controls(r.desc.control, r.input);
  if (r.desc.kind == RobotKind::UrdfTree) {
    r.joint_command = map_joint_controls(r.desc.control, r.input);
    set_tree_joints(r);
  } else {
    set_drive_speeds(r);
  }
  if (!r.arm_joints.empty() && r.desc.kind != RobotKind::UrdfTree) {
    r.arm_command = map_arm_controls(r.desc.control, r.input);
    set_arm_rates(r);
  }
  if (r.button_cues) update_button_cues(r);
}

// The belts' speeds or the wheel motors' rates from the drive command.
void Simulation::Impl::set_drive_speeds(Robot& r) {
  const RobotDescription& robot = r.desc;
  const DriveCommand& command = r.command;
  if (robot.kind == RobotKind::Tracked) {
    const auto& t = robot.tracks;
    double left = command.linear_mps - command.angular_radps * t.gauge_m / 2;
    double right = command.linear_mps + command.angular_radps * t.gauge_m / 2;
    // Saturate both sides together so the curvature the trainee asked for is kept.
    const double peak = std::max(std::fabs(left), std::fabs(right));
    if (peak > t.max_speed_mps) {
      left *= t.max_speed_mps / peak;
      right *= t.max_speed_mps / peak;
    }
    if (!command.enabled) left = right = 0.0;  // brake: stopped belts hold the ground
    r.track_speed_mps = {left * r.drive_factor[0], right * r.drive_factor[1]};
  } else {
    const auto& w = robot.wheels;
    double left = (command.linear_mps - command.angular_radps * w.track_m / 2) / w.radius_m;
    double right = (command.linear_mps + command.angular_radps * w.track_m / 2) / w.radius_m;
    const double peak = std::max(std::fabs(left), std::fabs(right));
    if (peak > w.max_speed_radps) {
      left *= w.max_speed_radps / peak;
      right *= w.max_speed_radps / peak;
    }
    if (!command.enabled) left = right = 0.0;  // brake: the motors hold the wheels
    left *= r.drive_factor[0];
    right *= r.drive_factor[1];
    for (std::size_t i = 0; i < 4; ++i) dJointSetHingeParam(r.hinges[i], dParamVel, (i % 2 == 0) ? left : right);
  }
}

// The arm joints' and the gripper's motor rates from the arm command.
void Simulation::Impl::set_arm_rates(Robot& r) {
  for (std::size_t i = 0; i < r.arm_joints.size(); ++i) {
    dJointID j = r.arm_joints[i].joint;
    if (!j) continue;
    if (r.arm_joints[i].slider) {
      dJointSetSliderParam(j, dParamVel, r.arm_command.gripper_mps);
    } else {
      // Joints are held (zero rate) whenever arm motion is not allowed.
      dJointSetHingeParam(j, dParamVel, r.arm_command.enabled ? r.arm_command.joint_radps[i] : 0.0);
    }
  }
}

// A horn sounds on the press, from a panel that can be trusted.
void Simulation::Impl::update_button_cues(Robot& r) {
  const ControlInput& input = r.input;
  const bool live = input.fresh && !input.failsafe;
  for (const auto& c : r.desc.sounds) {
    if (c.trigger != SoundTrigger::Button) continue;
    const bool down = live && pressed(input, c.button);
    const bool was = r.buttons_down.count(c.button) > 0;
    if (down && !was) {
      r.buttons_down.insert(c.button);
      cue(r, SoundTrigger::Button, "button " + c.button, 0.0, c.button);
    } else if (!down && was) {
      r.buttons_down.erase(c.button);
    }
  }
}

}  // namespace rise::sim
