// A urdf_tree robot's bodies and joints (sim/urdf_tree.hpp): one ODE body per
// group of links that fixed joints hold together, at its centre of mass and
// aligned with the world at zero joint positions; hinges for revolute and
// continuous joints, sliders for prismatic ones; the panel's joint commands
// on their motors.

#include <ode/ode.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/simulation_impl.hpp"

namespace rise::sim {
namespace {

Eigen::Isometry3d transform(const UrdfPose& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translate(Eigen::Vector3d(p.xyz_m[0], p.xyz_m[1], p.xyz_m[2]));
  T.rotate(Eigen::Quaterniond(p.wxyz[0], p.wxyz[1], p.wxyz[2], p.wxyz[3]));
  return T;
}

void to_ode(const Eigen::Matrix3d& R, dMatrix3 out) {
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) out[i * 4 + k] = R(i, k);
  for (int i = 0; i < 3; ++i) out[i * 4 + 3] = 0;
}

// The link's inertia as an ODE mass about the world origin, world axes.
dMass world_mass(const UrdfLink& l, const Eigen::Isometry3d& T_world_link) {
  dMass m;
  dMassSetZero(&m);
  if (!(l.mass_kg > 0)) return m;
  const auto& i = l.inertia_kgm2;
  dMassSetParameters(&m, l.mass_kg, 0, 0, 0, i[0], i[3], i[5], i[1], i[2], i[4]);
  const Eigen::Isometry3d T = T_world_link * transform(l.inertial_origin);
  dMatrix3 R;
  to_ode(T.rotation(), R);
  dMassRotate(&m, R);
  dMassTranslate(&m, T.translation().x(), T.translation().y(), T.translation().z());
  return m;
}

// Joint positions are read back by ODE as body1 relative to body2; the
// parent is body1, so the hinge axis is the URDF axis negated (a positive
// angle turns the child about +axis, as URDF has it).
dJointID make_joint(dWorldID world, const UrdfJoint& j, dBodyID parent, dBodyID child, const Eigen::Vector3d& anchor,
                    const Eigen::Vector3d& axis) {
  dJointID joint = nullptr;
  if (j.type == UrdfJointType::Prismatic) {
    joint = dJointCreateSlider(world, nullptr);
    dJointAttach(joint, parent, child);
    dJointSetSliderAxis(joint, -axis.x(), -axis.y(), -axis.z());
    dJointSetSliderParam(joint, dParamLoStop, j.lower);
    dJointSetSliderParam(joint, dParamHiStop, j.upper);
    dJointSetSliderParam(joint, dParamVel, 0.0);
    dJointSetSliderParam(joint, dParamFMax, j.friction);
    return joint;
  }
  joint = dJointCreateHinge(world, nullptr);
  dJointAttach(joint, parent, child);
  dJointSetHingeAnchor(joint, anchor.x(), anchor.y(), anchor.z());
  dJointSetHingeAxis(joint, -axis.x(), -axis.y(), -axis.z());
  // ODE's hinge stops work within ±π only; a wider revolute range stays unstopped.
  if (j.type == UrdfJointType::Revolute && j.lower >= -M_PI && j.upper <= M_PI) {
    dJointSetHingeParam(joint, dParamLoStop, j.lower);
    dJointSetHingeParam(joint, dParamHiStop, j.upper);
  }
  dJointSetHingeParam(joint, dParamVel, 0.0);
  dJointSetHingeParam(joint, dParamFMax, j.friction);  // uncommanded: static friction holds it
  return joint;
}

}  // namespace

void Simulation::Impl::build_urdf_tree(Robot& r, int index) {
  UrdfTree& tree = *r.desc.tree;
  const std::size_t n = tree.links.size();
  std::vector<Eigen::Isometry3d> T_world_link(n, Eigen::Isometry3d::Identity());
  for (std::size_t l = 1; l < n; ++l) {
    const UrdfJoint& j = tree.joints[l - 1];
    T_world_link[l] = T_world_link[j.parent] * transform(j.origin);
  }
  // Bodies: one per group of fixed links, its mass the group's.
  r.link_bodies.assign(n, nullptr);
  r.T_body_link.assign(n, Eigen::Isometry3d::Identity());
  std::vector<dMass> mass(n);
  for (auto& m : mass) dMassSetZero(&m);
  for (std::size_t l = 0; l < n; ++l) {
    const dMass m = world_mass(tree.links[l], T_world_link[l]);
    dMassAdd(&mass[tree.body_link(l)], &m);
  }
  for (std::size_t l = 0; l < n; ++l) {
    if (tree.body_link(l) != l) continue;
    dMass& m = mass[l];
    const double c[3] = {m.c[0], m.c[1], m.c[2]};
    dMassTranslate(&m, -c[0], -c[1], -c[2]);
    dBodyID b = dBodyCreate(world);
    dBodySetMass(b, &m);
    dBodySetPosition(b, c[0], c[1], c[2]);
    r.link_bodies[l] = b;
    r.bodies.push_back(b);
  }
  r.chassis = r.link_bodies[0];
  std::vector<dGeomID> geoms;
  for (std::size_t l = 0; l < n; ++l) {
    const std::size_t body_link = tree.body_link(l);
    dBodyID b = r.link_bodies[body_link];
    r.link_bodies[l] = b;
    const dReal* p = dBodyGetPosition(b);
    Eigen::Isometry3d T_world_body = Eigen::Isometry3d::Identity();
    T_world_body.translate(Eigen::Vector3d(p[0], p[1], p[2]));
    r.T_body_link[l] = T_world_body.inverse() * T_world_link[l];
    double friction = -1.0;
    for (const auto& [name, mu] : r.desc.link_friction)
      if (name == tree.links[l].name) friction = mu;
    for (UrdfShape& s : tree.links[l].collisions) {
      dGeomID g = nullptr;
      switch (s.type) {
        case UrdfShapeType::Box: g = dCreateBox(space, s.size_m[0], s.size_m[1], s.size_m[2]); break;
        case UrdfShapeType::Cylinder: g = dCreateCylinder(space, s.size_m[0], s.size_m[1]); break;
        case UrdfShapeType::Sphere: g = dCreateSphere(space, s.size_m[0]); break;
        case UrdfShapeType::Mesh: {
          if (s.mesh.triangles.empty()) continue;  // not loaded (a description parsed without meshes)
          dTriMeshDataID data = dGeomTriMeshDataCreate();
          dGeomTriMeshDataBuildSingle(data, s.mesh.vertices_m.data(), 3 * sizeof(float),
                                      static_cast<int>(s.mesh.vertex_count()), s.mesh.triangles.data(),
                                      static_cast<int>(s.mesh.triangles.size()), 3 * sizeof(uint32_t));
          r.trimeshes.push_back(data);
          g = dCreateTriMesh(space, data, nullptr, nullptr, nullptr);
          break;
        }
      }
      add_part(g, body_link == 0 ? GeomKind::Chassis : GeomKind::Arm, r, index, tree.links[l].name);
      infos.back()->friction = friction;
      dGeomSetBody(g, b);
      const Eigen::Isometry3d T = T_world_link[l] * transform(s.origin);
      dGeomSetOffsetWorldPosition(g, T.translation().x(), T.translation().y(), T.translation().z());
      dMatrix3 R;
      to_ode(T.rotation(), R);
      dGeomSetOffsetWorldRotation(g, R);
      geoms.push_back(g);
    }
  }
  // Joints: the moving ones are the robot's joint states, in URDF order.
  for (std::size_t k = 0; k < tree.joints.size(); ++k) {
    const UrdfJoint& j = tree.joints[k];
    if (j.type == UrdfJointType::Fixed) continue;
    const Eigen::Vector3d anchor = T_world_link[j.child].translation();
    const Eigen::Vector3d axis = T_world_link[j.child].rotation() * Eigen::Vector3d(j.axis[0], j.axis[1], j.axis[2]);
    dJointID joint = make_joint(world, j, r.link_bodies[j.parent], r.link_bodies[j.child], anchor, axis);
    add_arm_joint(r, index, j.name, joint, r.link_bodies[j.child], std::numeric_limits<double>::infinity());
    r.arm_joints.back().slider = j.type == UrdfJointType::Prismatic;
    Robot::TreeJoint t;
    t.urdf = k;
    t.continuous = j.type == UrdfJointType::Continuous;
    for (std::size_t c = 0; c < r.desc.control.joints.size(); ++c)
      if (r.desc.control.joints[c].joint == j.name) t.control = static_cast<int>(c);
    r.tree_joints.push_back(t);
  }
  r.arm_efforts.assign(r.arm_joints.size(), 0.0);
  lift_onto_ground(r, geoms);
}

// The tree is built around the root link's frame: raise it so that its
// lowest collision shape rests on the ground (z = 0).
void Simulation::Impl::lift_onto_ground(Robot& r, const std::vector<dGeomID>& geoms) {
  double low = std::numeric_limits<double>::infinity();
  for (dGeomID g : geoms) {
    dReal aabb[6];
    dGeomGetAABB(g, aabb);
    low = std::min(low, static_cast<double>(aabb[4]));
  }
  if (!std::isfinite(low)) return;
  const double dz = 0.001 - low;  // a millimetre up: it settles onto the ground in the first steps
  for (dBodyID b : r.bodies) {
    const dReal* p = dBodyGetPosition(b);
    dBodySetPosition(b, p[0], p[1], p[2] + dz);
  }
}

// Each controlled joint's motor from the panel's joint commands; the others
// hold with their URDF friction. Damping brakes every moving joint.
void Simulation::Impl::set_tree_joints(Robot& r) {
  const UrdfTree& tree = *r.desc.tree;
  for (std::size_t i = 0; i < r.tree_joints.size(); ++i) {
    dJointID j = r.arm_joints[i].joint;
    if (!j) continue;
    const UrdfJoint& u = tree.joints[r.tree_joints[i].urdf];
    const bool slider = r.arm_joints[i].slider;
    const double position = slider ? dJointGetSliderPosition(j) : dJointGetHingeAngle(j);
    const double rate = slider ? dJointGetSliderPositionRate(j) : dJointGetHingeAngleRate(j);
    double vel = 0.0, fmax = u.friction, effort = -u.damping * rate;
    if (const int c = r.tree_joints[i].control; c >= 0) {
      const JointControl& m = r.desc.control.joints[static_cast<std::size_t>(c)];
      const auto k = static_cast<std::size_t>(c);
      const bool on = r.joint_command.enabled[k];
      const double command = r.joint_command.values[k];
      const double vmax = u.velocity > 0 ? u.velocity : std::numeric_limits<double>::infinity();
      switch (m.mode) {
        case JointControlMode::Velocity:
          vel = std::clamp(command, -vmax, vmax);
          fmax = m.max_effort;
          break;
        case JointControlMode::Position:
          // Disabled: hold where it is (zero rate), as the arm does.
          vel = on ? std::clamp(m.gain_per_s * (std::clamp(command, u.lower, u.upper) - position), -vmax, vmax) : 0.0;
          fmax = m.max_effort;
          break;
        case JointControlMode::Effort:
          effort += std::clamp(command, -m.max_effort, m.max_effort);
          break;
      }
    }
    // The motor's sign follows ODE's joint position (see make_joint): a
    // positive rate turns the child about +axis; effort acts the same way.
    if (slider) {
      dJointSetSliderParam(j, dParamVel, vel);
      dJointSetSliderParam(j, dParamFMax, fmax);
      if (effort != 0.0) dJointAddSliderForce(j, effort);
    } else {
      dJointSetHingeParam(j, dParamVel, vel);
      dJointSetHingeParam(j, dParamFMax, fmax);
      if (effort != 0.0) dJointAddHingeTorque(j, effort);
    }
  }
}

// A continuous joint's position counts whole turns: ODE reads a hinge's
// angle within ±π, and one step turns it far less than π.
void Simulation::Impl::unwrap_tree_joints(Robot& r) {
  for (std::size_t i = 0; i < r.tree_joints.size(); ++i) {
    auto& t = r.tree_joints[i];
    if (!t.continuous || !r.arm_joints[i].joint) continue;
    const double now = dJointGetHingeAngle(r.arm_joints[i].joint);
    t.turned_rad += std::remainder(now - t.last_rad, 2 * M_PI);
    t.last_rad = now;
  }
}

std::vector<Eigen::Isometry3d> Simulation::T_world_links(std::size_t robot) const {
  std::vector<Eigen::Isometry3d> out;
  if (robot >= impl_->robots.size()) return out;
  const Impl::Robot& r = *impl_->robots[robot];
  for (std::size_t l = 0; l < r.link_bodies.size(); ++l) {
    const dReal* p = dBodyGetPosition(r.link_bodies[l]);
    const dReal* q = dBodyGetQuaternion(r.link_bodies[l]);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translate(Eigen::Vector3d(p[0], p[1], p[2]));
    T.rotate(Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized());
    out.push_back(T * r.T_body_link[l]);
  }
  return out;
}

}  // namespace rise::sim
