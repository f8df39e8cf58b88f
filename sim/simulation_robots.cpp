// The robots' bodies: the chassis, a skid-steer's four wheels, a tracked
// robot's belts, the arm with its gripper; built at the origin, then moved
// to the start pose.

#include <ode/ode.h>

#include <cmath>
#include <limits>

#include "sim/simulation_impl.hpp"

namespace rise::sim {
namespace {

constexpr int kTrackSegments = 2;  // capsules per track's bottom run (even: see build_tracked)
constexpr int kArmBreakSteps = 20;          // overload sustained this long breaks an arm joint
constexpr double kArmJointDamage = 0.25;

}  // namespace

// A robot part's geom, named "<id>/<part>" when the world holds several robots.
dGeomID Simulation::Impl::add_part(dGeomID g, GeomKind kind, const Robot& r, int index, const std::string& part,
                                   int side) {
  return add_geom(g, kind, robots.size() > 1 ? r.id + "/" + part : part, side, index);
}

void Simulation::Impl::build_chassis(Robot& r, int index, double chassis_z) {
  const auto& c = r.desc.chassis;
  r.chassis = dBodyCreate(world);
  dMass m;
  dMassSetBoxTotal(&m, c.mass_kg, c.size_m[0], c.size_m[1], c.size_m[2]);
  dBodySetMass(r.chassis, &m);
  dBodySetPosition(r.chassis, 0, 0, chassis_z);
  dGeomSetBody(add_part(dCreateBox(space, c.size_m[0], c.size_m[1], c.size_m[2]), GeomKind::Chassis, r, index, "chassis"),
               r.chassis);
  r.bodies.push_back(r.chassis);
}

void Simulation::Impl::build_skid_steer(Robot& r, int index) {
  const auto& c = r.desc.chassis;
  const auto& w = r.desc.wheels;
  auto& wheels = r.wheels;
  auto& hinges = r.hinges;
  build_chassis(r, index, c.clearance_m + c.size_m[2] / 2);
  const double xs[4] = {w.wheelbase_m / 2, w.wheelbase_m / 2, -w.wheelbase_m / 2, -w.wheelbase_m / 2};
  const double ys[4] = {w.track_m / 2, -w.track_m / 2, w.track_m / 2, -w.track_m / 2};
  dMatrix3 R;
  dRFromAxisAndAngle(R, 1, 0, 0, M_PI / 2);  // cylinder axis (z) along the body's y
  for (std::size_t i = 0; i < 4; ++i) {
    wheels[i] = dBodyCreate(world);
    dMass wm;
    dMassSetCylinderTotal(&wm, w.mass_kg, 3, w.radius_m, w.width_m);
    dBodySetMass(wheels[i], &wm);
    dBodySetPosition(wheels[i], xs[i], ys[i], w.radius_m);
    dBodySetRotation(wheels[i], R);
    dGeomSetBody(add_part(dCreateCylinder(space, w.radius_m, w.width_m), GeomKind::Wheel, r, index, kWheelNames[i],
                          static_cast<int>(i % 2)),
                 wheels[i]);
    r.bodies.push_back(wheels[i]);
    hinges[i] = dJointCreateHinge(world, nullptr);
    dJointAttach(hinges[i], r.chassis, wheels[i]);
    dJointSetHingeAnchor(hinges[i], xs[i], ys[i], w.radius_m);
    // Axis along -y: a positive motor speed rolls the robot forward (+x).
    dJointSetHingeAxis(hinges[i], 0, -1, 0);
    dJointSetHingeParam(hinges[i], dParamFMax, w.max_torque_nm);
    dJointSetHingeParam(hinges[i], dParamVel, 0.0);
    dJointSetFeedback(hinges[i], &r.feedback[i]);
  }
}

// Tracks are geoms of the chassis body (no track joints): their contacts
// carry the track speed as surface motion.
void Simulation::Impl::build_tracked(Robot& r, int index) {
  const auto& c = r.desc.chassis;
  const auto& t = r.desc.tracks;
  const double chassis_z = c.clearance_m + c.size_m[2] / 2;
  build_chassis(r, index, chassis_z);
  dMatrix3 along_x;  // capsule axis (z) along the body's x
  dRFromAxisAndAngle(along_x, 0, 1, 0, M_PI / 2);
  dMatrix3 rising;  // capsule axis along the front run, rising at approach_rad
  dRFromAxisAndAngle(rising, 0, 1, 0, M_PI / 2 - t.approach_rad);
  for (int side = 0; side < 2; ++side) {
    const double y = side == 0 ? t.gauge_m / 2 : -t.gauge_m / 2;
    const auto name = kTrackNames[static_cast<std::size_t>(side)];
    // The bottom run in segments: a single capsule bears only at its two
    // ends, and Coulomb friction then pins a turn in place on whichever end
    // is loaded more; an even number of segments puts a bearing point under
    // the centre, where the loads balance.
    const double segment = t.length_m / kTrackSegments;
    for (int k = 0; k < kTrackSegments; ++k) {
      dGeomID bottom = add_part(dCreateCapsule(space, t.radius_m, segment), GeomKind::Track, r, index, name, side);
      dGeomSetBody(bottom, r.chassis);
      dGeomSetOffsetPosition(bottom, -t.length_m / 2 + (k + 0.5) * segment, y, t.radius_m - chassis_z);
      dGeomSetOffsetRotation(bottom, along_x);
    }
    if (t.approach_length_m > 0) {
      dGeomID front =
          add_part(dCreateCapsule(space, t.radius_m, t.approach_length_m), GeomKind::Track, r, index, name, side);
      dGeomSetBody(front, r.chassis);
      // Starts one radius up the run, so that at rest only the bottom run
      // bears on flat ground (the load spreads over the whole track).
      const double from = t.radius_m + t.approach_length_m / 2;
      dGeomSetOffsetPosition(front, t.length_m / 2 + std::cos(t.approach_rad) * from, y,
                             t.radius_m + std::sin(t.approach_rad) * from - chassis_z);
      dGeomSetOffsetRotation(front, rising);
    }
  }
}

dBodyID Simulation::Impl::link_body(Robot& r, int index, const std::string& name, double mass_kg, double sx, double sy,
                                    double sz, const double pos[3], double pitch_up_rad) {
  dBodyID b = dBodyCreate(world);
  dMass m;
  dMassSetBoxTotal(&m, mass_kg, sx, sy, sz);
  dBodySetMass(b, &m);
  dBodySetPosition(b, pos[0], pos[1], pos[2]);
  dMatrix3 R;
  dRFromAxisAndAngle(R, 0, 1, 0, -pitch_up_rad);
  dBodySetRotation(b, R);
  dGeomSetBody(add_part(dCreateBox(space, sx, sy, sz), GeomKind::Arm, r, index, name), b);
  r.bodies.push_back(b);
  return b;
}

void Simulation::Impl::add_arm_joint(Robot& r, int index, const std::string& name, dJointID j, dBodyID child,
                                     double break_nm) {
  Breakable b;
  b.owner = r.id;
  b.robot = index;
  b.name = name;
  b.joint = j;
  b.child = child;
  b.break_load_nm = break_nm;
  b.break_steps = kArmBreakSteps;
  b.damage = kArmJointDamage;
  ArmJoint a;
  a.joint = j;
  a.breakable = breakables.size();
  breakables.push_back(b);
  dJointSetFeedback(breakables.back().joint, &breakables.back().feedback);
  r.arm_joints.push_back(a);
}

void Simulation::Impl::build_arm(Robot& r, int index) {
  const ArmDescription& a = *r.desc.arm;
  const ArmMapping& m = *r.desc.control.arm;
  const auto& c = r.desc.chassis;
  auto& arm_joints = r.arm_joints;
  const double top = c.clearance_m + c.size_m[2];
  const double w = a.link_width_m;
  const double turret_h = 0.08;
  const double base[3] = {a.mount_m[0], a.mount_m[1], top + turret_h / 2};
  dBodyID turret = link_body(r, index, "arm_turret", a.link_mass_kg, 0.14, 0.14, turret_h, base, 0.0);
  const double shoulder[3] = {a.mount_m[0], a.mount_m[1], top + turret_h};
  const double up = M_PI / 4;
  const double upper_c[3] = {shoulder[0] + std::cos(up) * a.upper_length_m / 2, shoulder[1],
                             shoulder[2] + std::sin(up) * a.upper_length_m / 2};
  dBodyID upper = link_body(r, index, "arm_upper", a.link_mass_kg, a.upper_length_m, w, w, upper_c, up);
  const double elbow[3] = {shoulder[0] + std::cos(up) * a.upper_length_m, shoulder[1],
                           shoulder[2] + std::sin(up) * a.upper_length_m};
  const double fore_c[3] = {elbow[0] + a.forearm_length_m / 2, elbow[1], elbow[2]};
  dBodyID fore = link_body(r, index, "arm_forearm", a.link_mass_kg, a.forearm_length_m, w, w, fore_c, 0.0);
  // The fixed jaw is a second geom of the forearm at its tip, hanging down.
  const double jaw_h = 0.12;
  dGeomID jaw = add_part(dCreateBox(space, 0.03, 0.02, jaw_h), GeomKind::Arm, r, index, "gripper_jaw");
  dGeomSetBody(jaw, fore);
  dGeomSetOffsetPosition(jaw, a.forearm_length_m / 2, -a.gripper_stroke_m / 2, -jaw_h / 2);
  const double finger_c[3] = {fore_c[0] + a.forearm_length_m / 2, elbow[1] + a.gripper_stroke_m / 2,
                              elbow[2] - jaw_h / 2};
  r.finger = link_body(r, index, "gripper_finger", 0.3, 0.03, 0.02, jaw_h, finger_c, 0.0);

  // Hinge axes: ODE's hinge angle is body1's rotation relative to body2
  // about the axis, so with the parent as body1 the child turns about
  // −axis for a positive angle: −z makes yaw counter-clockwise, +y makes
  // pitch raise the arm.
  dJointID yaw = dJointCreateHinge(world, nullptr);
  dJointAttach(yaw, r.chassis, turret);
  dJointSetHingeAnchor(yaw, base[0], base[1], top);
  dJointSetHingeAxis(yaw, 0, 0, -1);
  add_arm_joint(r, index, "shoulder_yaw", yaw, turret, m.joints[0].break_torque_nm);
  dJointID pitch = dJointCreateHinge(world, nullptr);
  dJointAttach(pitch, turret, upper);
  dJointSetHingeAnchor(pitch, shoulder[0], shoulder[1], shoulder[2]);
  dJointSetHingeAxis(pitch, 0, 1, 0);
  add_arm_joint(r, index, "shoulder_pitch", pitch, upper, m.joints[1].break_torque_nm);
  dJointID el = dJointCreateHinge(world, nullptr);
  dJointAttach(el, upper, fore);
  dJointSetHingeAnchor(el, elbow[0], elbow[1], elbow[2]);
  dJointSetHingeAxis(el, 0, 1, 0);
  add_arm_joint(r, index, "elbow_pitch", el, fore, m.joints[2].break_torque_nm);
  for (std::size_t i = 0; i < 3; ++i) {
    dJointID j = arm_joints[i].joint;
    dJointSetHingeParam(j, dParamLoStop, m.joints[i].min_rad);
    dJointSetHingeParam(j, dParamHiStop, m.joints[i].max_rad);
    dJointSetHingeParam(j, dParamFMax, m.joints[i].max_torque_nm);
    dJointSetHingeParam(j, dParamVel, 0.0);
  }
  // Gripper: position 0 = open; closing (negative) moves the finger to the jaw.
  dJointID grip = dJointCreateSlider(world, nullptr);
  dJointAttach(grip, fore, r.finger);
  dJointSetSliderAxis(grip, 0, 1, 0);
  dJointSetSliderParam(grip, dParamLoStop, -a.gripper_stroke_m);
  dJointSetSliderParam(grip, dParamHiStop, 0.0);
  dJointSetSliderParam(grip, dParamFMax, m.gripper_max_force_n);
  dJointSetSliderParam(grip, dParamVel, 0.0);
  // The gripper's slide is not a breakable joint: its force is capped by the motor.
  add_arm_joint(r, index, "gripper", grip, r.finger, std::numeric_limits<double>::infinity());
  arm_joints.back().slider = true;
  r.arm_efforts.assign(arm_joints.size(), 0.0);
}

// Moves every body of the robot rigidly from the origin to its start pose
// (joint anchors and axes are stored body-relative, so they follow).
void Simulation::Impl::place_robot(Robot& r) {
  const double yaw = r.start.yaw_rad;
  const double tx = r.start.xy_m[0], ty = r.start.xy_m[1];
  if (yaw == 0.0 && tx == 0.0 && ty == 0.0) return;
  dMatrix3 Ryaw;
  dRFromAxisAndAngle(Ryaw, 0, 0, 1, yaw);
  const double c = std::cos(yaw), s = std::sin(yaw);
  for (dBodyID b : r.bodies) {
    const dReal* p = dBodyGetPosition(b);
    dBodySetPosition(b, c * p[0] - s * p[1] + tx, s * p[0] + c * p[1] + ty, p[2]);
    dMatrix3 R;
    dMultiply0_333(R, Ryaw, dBodyGetRotation(b));
    dBodySetRotation(b, R);
  }
}

}  // namespace rise::sim
