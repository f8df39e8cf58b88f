// The contact model: which geoms meet, the touches that become collision
// events, and each contact's friction (anisotropic tyres, track belts as
// surface motion, soft contacts).

#include <ode/ode.h>

#include <algorithm>
#include <cmath>

#include "sim/simulation_impl.hpp"

namespace rise::sim {
namespace {

// Contact springs for a 1 ms step: stiffness kp and damping kd turned into
// ODE's ERP/CFM (ODE manual, "Soft constraint and constraint force mixing").
constexpr double kContactKp = 2.0e5;  // N/m
constexpr double kContactKd = 2.0e3;  // N·s/m
constexpr double kLateralFrictionRatio = 0.6;  // tyre side grip vs rolling grip, lets skid steering turn
constexpr double kObstacleFriction = 0.5;
constexpr int kMaxContacts = 4;

// The speed (m/s) at which two geoms' bodies approach along the contact
// normal at the contact point (0 for two resting surfaces).
double approach_speed_mps(const dContactGeom& c) {
  dVector3 va{0, 0, 0, 0}, vb{0, 0, 0, 0};
  if (dBodyID b1 = dGeomGetBody(c.g1)) dBodyGetPointVel(b1, c.pos[0], c.pos[1], c.pos[2], va);
  if (dBodyID b2 = dGeomGetBody(c.g2)) dBodyGetPointVel(b2, c.pos[0], c.pos[1], c.pos[2], vb);
  return std::fabs((va[0] - vb[0]) * c.normal[0] + (va[1] - vb[1]) * c.normal[1] + (va[2] - vb[2]) * c.normal[2]);
}

}  // namespace

void Simulation::Impl::near_callback(void* data, dGeomID a, dGeomID b) { static_cast<Impl*>(data)->collide(a, b); }

bool Simulation::Impl::may_touch(dGeomID a, dGeomID b, const GeomInfo& ia, const GeomInfo& ib) {
  if (is_static(ia.kind) && is_static(ib.kind)) return false;
  // A robot's own parts never collide; two robots do.
  if (is_robot(ia.kind) && is_robot(ib.kind) && ia.robot == ib.robot) return false;
  // The door hangs in its frame just above the floor: it only meets the
  // robots and objects (and the floor once it has come off its hinge).
  const auto door_vs_static = [](const GeomInfo& door, const GeomInfo& other) {
    return door.kind == GeomKind::Door && is_static(other.kind) && !(door.loose && other.kind == GeomKind::Ground);
  };
  if (door_vs_static(ia, ib) || door_vs_static(ib, ia)) return false;
  const dBodyID ba = dGeomGetBody(a), bb = dGeomGetBody(b);
  return !(ba && bb && dAreConnectedExcluding(ba, bb, dJointTypeContact));
}

void Simulation::Impl::collide(dGeomID a, dGeomID b) {
  const auto* ia = static_cast<const GeomInfo*>(dGeomGetData(a));
  const auto* ib = static_cast<const GeomInfo*>(dGeomGetData(b));
  if (!may_touch(a, b, *ia, *ib)) return;
  // A robot part goes first: g1 of every contact is a robot's, so the
  // surface motion below is the track's own. Between two robots a track
  // goes first, else the robot listed first.
  const bool robot_pair = is_robot(ia->kind) && is_robot(ib->kind);
  bool swap = is_robot(ib->kind);
  if (robot_pair) {
    const bool track_a = ia->kind == GeomKind::Track, track_b = ib->kind == GeomKind::Track;
    swap = track_a != track_b ? track_b : ib->robot < ia->robot;
  }
  if (swap) {
    std::swap(a, b);
    std::swap(ia, ib);
  }

  dContact contact[kMaxContacts];
  const int n = dCollide(a, b, kMaxContacts, &contact[0].geom, sizeof(dContact));
  if (n <= 0) return;
  const bool robot_contact = is_robot(ia->kind);
  if (robot_contact && ib->kind != GeomKind::Ground) record_touch(*ia, *ib, contact, n);

  const Robot* owner = robot_contact ? robots[static_cast<std::size_t>(ia->robot)].get() : nullptr;
  double forward[3] = {1, 0, 0};  // the robot's chassis x axis in the world
  if (owner) {
    const dReal* R = dBodyGetRotation(owner->chassis);
    forward[0] = R[0];
    forward[1] = R[4];
    forward[2] = R[8];
  }
  for (int i = 0; i < n; ++i) {
    set_surface(contact[i], *ia, *ib, owner, forward);
    dJointID j = dJointCreateContact(world, contacts, &contact[i]);
    dJointAttach(j, dGeomGetBody(contact[i].geom.g1), dGeomGetBody(contact[i].geom.g2));
  }
}

// A robot part (ia) touching something other than the ground: what both
// robots touch, and this step's touch for the collision events.
void Simulation::Impl::record_touch(const GeomInfo& ia, const GeomInfo& ib, const dContact* contact, int n) {
  const bool robot_pair = is_robot(ib.kind);
  double impact = 0.0;
  for (int i = 0; i < n; ++i) impact = std::max(impact, approach_speed_mps(contact[i].geom));
  robots[static_cast<std::size_t>(ia.robot)]->touching.insert(ib.name);
  if (robot_pair) robots[static_cast<std::size_t>(ib.robot)]->touching.insert(ia.name);
  // Events name the first-listed robot's part first.
  const bool ordered = !robot_pair || ia.robot < ib.robot;
  const GeomInfo& first = ordered ? ia : ib;
  const GeomInfo& second = ordered ? ib : ia;
  Touch& t = seen[Pair(first.name, second.name)];
  t.robot_a = first.robot;
  t.robot_b = robot_pair ? second.robot : -1;
  t.impact_mps = std::max(t.impact_mps, impact);
}

// One contact's surface: soft (kContactKp, kContactKd), with the friction of
// what meets (ia is the robot's part when a robot is involved; owner its
// robot, forward its chassis x axis in the world).
void Simulation::Impl::set_surface(dContact& contact, const GeomInfo& ia, const GeomInfo& ib, const Robot* owner,
                                   const double forward[3]) const {
  const double erp = kStepS * kContactKp / (kStepS * kContactKp + kContactKd);
  const double cfm = 1.0 / (kStepS * kContactKp + kContactKd);
  const bool on_ground = ib.kind == GeomKind::Ground;
  dSurfaceParameters& s = contact.surface;
  s.mode = dContactApprox1 | dContactSoftERP | dContactSoftCFM;
  s.mu = kObstacleFriction;
  s.soft_erp = erp;
  s.soft_cfm = cfm;
  if (ia.kind == GeomKind::Wheel) {
    // Tyre friction is anisotropic: rolling direction along the chassis' x.
    const double mu =
        (on_ground ? std::min(owner->desc.wheels.friction, world_desc.ground_friction) : kObstacleFriction) *
        owner->grip_factor[static_cast<std::size_t>(ia.side)];
    s.mu = mu;
    s.mode |= dContactMu2 | dContactFDir1;
    s.mu2 = mu * kLateralFrictionRatio;
    contact.fdir1[0] = forward[0];
    contact.fdir1[1] = forward[1];
    contact.fdir1[2] = forward[2];
  } else if (ia.kind == GeomKind::Track) {
    // Contact surface motion (Pecka et al. 2017; Gazebo's
    // SimpleTrackedVehicle): the belt's direction is the chassis' forward
    // axis projected onto the contact plane, so that at a step's nose the
    // belt pulls the robot up as well as forward. ODE makes the relative
    // tangential velocity of body1 (the track) along fdir1 equal motion1.
    const dReal* nrm = contact.geom.normal;
    const double along = forward[0] * nrm[0] + forward[1] * nrm[1] + forward[2] * nrm[2];
    double f[3] = {forward[0] - along * nrm[0], forward[1] - along * nrm[1], forward[2] - along * nrm[2]};
    const double len = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    const double mu_ground =
        (on_ground ? world_desc.ground_friction : 1.0) * owner->grip_factor[static_cast<std::size_t>(ia.side)];
    s.mu = owner->desc.tracks.friction * mu_ground;
    if (len > 0.2) {  // a face square to the track (a wall ahead) gets plain friction
      s.mode |= dContactMu2 | dContactFDir1 | dContactMotion1;
      s.mu2 = owner->desc.tracks.lateral_friction * mu_ground;
      for (int k = 0; k < 3; ++k) contact.fdir1[k] = f[k] / len;
      s.motion1 = owner->track_speed_mps[static_cast<std::size_t>(ia.side)];
    }
  } else if (ia.friction >= 0.0) {
    s.mu = ia.friction * (on_ground ? world_desc.ground_friction : 1.0);
  } else if (!is_robot(ia.kind) || on_ground) {
    s.mu = world_desc.ground_friction * kObstacleFriction * 2.0;
  }
}

}  // namespace rise::sim
