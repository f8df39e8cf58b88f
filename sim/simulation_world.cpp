// The world's geoms and bodies: ground, static boxes (boxes, props, walls,
// ceiling), stairs, hinged doors and movable objects.

#include <ode/ode.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/simulation_impl.hpp"

namespace rise::sim {
namespace {

constexpr double kDoorGapM = 0.01;  // door bottom above the floor

void set_yaw(dGeomID g, double yaw_rad) {
  dMatrix3 R;
  dRFromAxisAndAngle(R, 0, 0, 1, yaw_rad);
  dGeomSetRotation(g, R);
}

}  // namespace

dGeomID Simulation::Impl::add_geom(dGeomID g, GeomKind kind, const std::string& name, int side, int robot) {
  infos.push_back(std::make_unique<GeomInfo>(GeomInfo{kind, name, side, false, robot}));
  dGeomSetData(g, infos.back().get());
  return g;
}

void Simulation::Impl::add_static_box(const std::string& name, double cx, double cy, double cz, double sx, double sy,
                                      double sz, double yaw) {
  dGeomID g = add_geom(dCreateBox(static_space, sx, sy, sz), GeomKind::Obstacle, name);
  dGeomSetPosition(g, cx, cy, cz);
  set_yaw(g, yaw);
}

void Simulation::Impl::add_static_box(const BoxObstacle& b) {
  add_static_box(b.name, b.center_m[0], b.center_m[1], b.center_m[2], b.size_m[0], b.size_m[1], b.size_m[2],
                 b.yaw_rad);
}

void Simulation::Impl::build_world() {
  add_geom(dCreatePlane(static_space, 0, 0, 1, 0), GeomKind::Ground, "ground");
  for (const auto& b : world_desc.boxes) add_static_box(b);
  for (const auto& p : world_desc.props) add_static_box(p.box);
  for (const auto& w : world_desc.walls)
    for (const auto& b : wall_boxes(w)) add_static_box(b);
  if (world_desc.ceiling) add_static_box(ceiling_box(*world_desc.ceiling));
  for (const auto& s : world_desc.stairs) build_stairs(s);
  for (const auto& d : world_desc.doors) build_door(d);
  for (const auto& o : world_desc.objects) build_object(o);
}

void Simulation::Impl::build_stairs(const Stairs& s) {
  const double c = std::cos(s.yaw_rad), sn = std::sin(s.yaw_rad);
  // Solid blocks from the floor up: step i spans tread i and rises (i+1) risers.
  for (int i = 0; i <= s.steps; ++i) {
    const bool landing = i == s.steps;
    const double along0 = i * s.tread_m;
    const double length = landing ? s.landing_m : s.tread_m;
    const double height = landing ? s.landing_height_m() : (i + 1) * s.riser_m;
    const double along = along0 + length / 2;
    add_static_box(s.name, s.start_m[0] + c * along, s.start_m[1] + sn * along, height / 2, length, s.width_m,
                   height, s.yaw_rad);
  }
}

void Simulation::Impl::build_door(const Door& d) {
  DoorBody door;
  door.desc = &d;
  door.body = dBodyCreate(world);
  dMass m;
  dMassSetBoxTotal(&m, d.mass_kg, d.width_m, d.thickness_m, d.height_m);
  dBodySetMass(door.body, &m);
  const double c = std::cos(d.yaw_rad), sn = std::sin(d.yaw_rad);
  dBodySetPosition(door.body, d.hinge_m[0] + c * d.width_m / 2, d.hinge_m[1] + sn * d.width_m / 2,
                   kDoorGapM + d.height_m / 2);
  dMatrix3 R;
  dRFromAxisAndAngle(R, 0, 0, 1, d.yaw_rad);
  dBodySetRotation(door.body, R);
  dGeomSetBody(add_geom(dCreateBox(space, d.width_m, d.thickness_m, d.height_m), GeomKind::Door, d.name), door.body);
  door.info = infos.back().get();
  Breakable hinge;
  hinge.owner = d.name;
  hinge.name = "hinge";
  hinge.joint = dJointCreateHinge(world, nullptr);
  dJointAttach(hinge.joint, door.body, nullptr);
  dJointSetHingeAnchor(hinge.joint, d.hinge_m[0], d.hinge_m[1], kDoorGapM + d.height_m / 2);
  dJointSetHingeAxis(hinge.joint, 0, 0, 1);
  dJointSetHingeParam(hinge.joint, dParamLoStop, -d.open_max_rad);
  dJointSetHingeParam(hinge.joint, dParamHiStop, d.open_max_rad);
  // A motor held at zero speed with a small force limit is hinge friction.
  dJointSetHingeParam(hinge.joint, dParamVel, 0.0);
  dJointSetHingeParam(hinge.joint, dParamFMax, d.friction_torque_nm);
  hinge.child = door.body;
  hinge.child_is_body1 = true;
  hinge.break_load_nm = d.break_torque_nm;
  hinge.break_steps = std::max(1, static_cast<int>(std::lround(d.break_time_ms / (kStepS * 1000.0))));
  door.hinge = breakables.size();
  breakables.push_back(hinge);
  dJointSetFeedback(breakables.back().joint, &breakables.back().feedback);
  doors.push_back(door);
}

void Simulation::Impl::build_object(const MovableObject& o) {
  ObjectBody ob;
  ob.desc = &o;
  ob.body = dBodyCreate(world);
  dMass m;
  dMassSetBoxTotal(&m, o.mass_kg, o.size_m[0], o.size_m[1], o.size_m[2]);
  dBodySetMass(ob.body, &m);
  dBodySetPosition(ob.body, o.center_m[0], o.center_m[1], o.center_m[2]);
  dGeomSetBody(add_geom(dCreateBox(space, o.size_m[0], o.size_m[1], o.size_m[2]), GeomKind::Object, o.name), ob.body);
  objects.push_back(ob);
}

// The doors' return springs (a door on its hinge swings back to closed).
void Simulation::Impl::apply_door_return_torques() {
  for (auto& d : doors) {
    const Breakable& h = breakables[d.hinge];
    if (!h.broken()) dJointAddHingeTorque(h.joint, -d.desc->return_nm_per_rad * dJointGetHingeAngle(h.joint));
  }
}

double Simulation::door_angle_rad(const std::string& door) const {
  for (const auto& d : impl_->doors) {
    if (d.desc->name != door) continue;
    const auto& h = impl_->breakables[d.hinge];
    if (h.broken()) {
      // Off its hinge: report the panel's yaw relative to its frame.
      const dReal* R = dBodyGetRotation(d.body);
      return std::remainder(std::atan2(R[4], R[0]) - d.desc->yaw_rad, 2 * M_PI);
    }
    return dJointGetHingeAngle(h.joint);
  }
  return std::numeric_limits<double>::quiet_NaN();
}

std::array<double, 3> Simulation::object_position_m(const std::string& object) const {
  for (const auto& o : impl_->objects) {
    if (o.desc->name != object) continue;
    const dReal* p = dBodyGetPosition(o.body);
    return {p[0], p[1], p[2]};
  }
  for (const auto& d : impl_->doors) {
    if (d.desc->name != object) continue;
    const dReal* p = dBodyGetPosition(d.body);
    return {p[0], p[1], p[2]};
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  return {nan, nan, nan};
}

}  // namespace rise::sim
