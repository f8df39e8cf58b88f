// Loads on joints, from ODE's joint feedback: the arm's motor efforts, and
// joints (arm joints, door hinges) that break when overloaded for long enough.

#include <ode/ode.h>

#include <algorithm>
#include <cmath>

#include "sim/simulation_impl.hpp"

namespace rise::sim {
namespace {

// Load on a joint: the constraint wrench it applies to `body`, taken about
// the joint anchor (N·m). ODE reports the torque about the body's centre of
// mass; moving it to the anchor adds (com − anchor) × force.
double joint_load_nm(dBodyID body, const dVector3 anchor, const dReal* force, const dReal* torque) {
  const dReal* c = dBodyGetPosition(body);
  const double r[3] = {c[0] - anchor[0], c[1] - anchor[1], c[2] - anchor[2]};
  const double t[3] = {torque[0] + r[1] * force[2] - r[2] * force[1], torque[1] + r[2] * force[0] - r[0] * force[2],
                       torque[2] + r[0] * force[1] - r[1] * force[0]};
  return std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
}

std::string newton_metres(double v) {
  const auto whole = static_cast<long long>(std::lround(v));
  return "load " + std::to_string(whole) + " N·m";
}

}  // namespace

void Simulation::Impl::check_breakables() {
  for (auto& b : breakables) {
    if (b.broken()) continue;
    dVector3 anchor;
    if (dJointGetType(b.joint) == dJointTypeHinge) {
      dJointGetHingeAnchor(b.joint, anchor);
    } else {
      const dReal* p = dBodyGetPosition(b.child);
      anchor[0] = p[0];
      anchor[1] = p[1];
      anchor[2] = p[2];
    }
    const dReal* f = b.child_is_body1 ? b.feedback.f1 : b.feedback.f2;
    const dReal* t = b.child_is_body1 ? b.feedback.t1 : b.feedback.t2;
    const double load = joint_load_nm(b.child, anchor, f, t);
    b.over_steps = load > b.break_load_nm ? b.over_steps + 1 : 0;
    if (b.over_steps >= b.break_steps) break_joint(b, load);
  }
}

// Destroys the joint: a door comes off its hinge; a robot's arm joint goes
// limp and adds its damage.
void Simulation::Impl::break_joint(Breakable& b, double load) {
  dJointDestroy(b.joint);
  b.joint = nullptr;
  for (auto& d : doors)
    if (&breakables[d.hinge] == &b) d.info->loose = true;
  emit(SimEventKind::JointBroken, b.owner, b.name, newton_metres(load));
  if (b.robot >= 0) {
    Robot& r = *robots[static_cast<std::size_t>(b.robot)];
    for (auto& a : r.arm_joints)
      if (&breakables[a.breakable] == &b) a.joint = nullptr;
    r.damage = std::min(1.0, r.damage + b.damage);
    cue(r, SoundTrigger::JointBroken, "joint_broken " + b.name + " " + newton_metres(load));
  }
}

// Motor + limit effort along each arm joint's axis, on the child (a
// urdf_tree's: along its URDF axis).
void Simulation::Impl::update_arm_efforts(Robot& r) {
  for (std::size_t i = 0; i < r.arm_joints.size(); ++i) {
    const Breakable& b = breakables[r.arm_joints[i].breakable];
    if (!r.arm_joints[i].joint) {
      r.arm_efforts[i] = 0.0;
      continue;
    }
    dVector3 axis;
    const dReal* t = r.arm_joints[i].slider ? b.feedback.f2 : b.feedback.t2;
    if (r.arm_joints[i].slider) dJointGetSliderAxis(r.arm_joints[i].joint, axis);
    else dJointGetHingeAxis(r.arm_joints[i].joint, axis);
    r.arm_efforts[i] = t[0] * axis[0] + t[1] * axis[1] + t[2] * axis[2];
    if (i < r.tree_joints.size()) {
      // A urdf_tree hinge's effort is taken about its anchor, where the
      // constraint force has no moment: ODE's t2 is about the child's centre
      // of mass, so add (com - anchor) x f2. Its ODE axis is the URDF axis
      // negated (simulation_tree.cpp make_joint).
      if (!r.arm_joints[i].slider) {
        dVector3 anchor;
        dJointGetHingeAnchor(r.arm_joints[i].joint, anchor);
        const dReal* c = dBodyGetPosition(b.child);
        const dReal* f = b.feedback.f2;
        const double d[3] = {c[0] - anchor[0], c[1] - anchor[1], c[2] - anchor[2]};
        const double m[3] = {d[1] * f[2] - d[2] * f[1], d[2] * f[0] - d[0] * f[2], d[0] * f[1] - d[1] * f[0]};
        r.arm_efforts[i] += m[0] * axis[0] + m[1] * axis[1] + m[2] * axis[2];
      }
      r.arm_efforts[i] = -r.arm_efforts[i];
    }
  }
}

}  // namespace rise::sim
