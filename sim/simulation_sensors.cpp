// What the robots' sensors read from the world: odometry from the belts or
// wheels, the IMU from the chassis, ray casts for the laser scanner, and
// the true base and camera poses.

#include <ode/ode.h>

#include <algorithm>
#include <limits>

#include "sim/simulation_impl.hpp"

namespace rise::sim {

struct Simulation::Impl::RayHit {
  dGeomID ray;
  double range_m;
  int own_robot;
};

void Simulation::Impl::ray_callback(void* data, dGeomID a, dGeomID b) {
  auto* hit = static_cast<RayHit*>(data);
  const dGeomID other = a == hit->ray ? b : a;
  const auto* info = static_cast<const GeomInfo*>(dGeomGetData(other));
  if (!info || (is_robot(info->kind) && info->robot == hit->own_robot)) return;
  dContactGeom c;
  if (dCollide(hit->ray, other, 1, &c, sizeof(dContactGeom)) > 0) hit->range_m = std::min(hit->range_m, c.depth);
}

double Simulation::Impl::cast_ray_m(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_range_m,
                                    std::size_t own_robot) {
  const double inf = std::numeric_limits<double>::infinity();
  if (!(max_range_m > 0.0)) return inf;
  dGeomRaySetLength(ray, max_range_m);
  dGeomRaySet(ray, o[0], o[1], o[2], d[0], d[1], d[2]);
  RayHit hit{ray, inf, static_cast<int>(own_robot)};
  dSpaceCollide2(ray, reinterpret_cast<dGeomID>(static_space), &hit, &ray_callback);
  dSpaceCollide2(ray, reinterpret_cast<dGeomID>(space), &hit, &ray_callback);
  return hit.range_m <= max_range_m ? hit.range_m : inf;
}

Eigen::Isometry3d Simulation::Impl::T_world_base(const Robot& r) {
  const dReal* p = dBodyGetPosition(r.chassis);
  const dReal* q = dBodyGetQuaternion(r.chassis);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translate(Eigen::Vector3d(p[0], p[1], p[2]));
  T.rotate(Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized());
  // A urdf_tree's base frame is its root link's, not its body's centre of mass.
  return r.T_body_link.empty() ? T : T * r.T_body_link[0];
}

// Left and right belt speeds (tracks) or mean rim speeds of each side's
// wheels (fl, fr, rl, rr), m/s.
std::array<double, 2> Simulation::Impl::side_speeds_mps(const Robot& r) {
  if (r.desc.kind == RobotKind::Tracked) return r.track_speed_mps;
  if (r.desc.kind == RobotKind::UrdfTree) {
    // No fixed running gear: the base's forward and turn rates, as the two
    // sides of a 1 m gauge (the gauge Simulation::Impl::build gives its odometry).
    const dReal* v = dBodyGetLinearVel(r.chassis);
    const dReal* w = dBodyGetAngularVel(r.chassis);
    const Eigen::Isometry3d T = T_world_base(r);
    const double forward = T.linear().col(0).dot(Eigen::Vector3d(v[0], v[1], v[2]));
    const double turn = T.linear().col(2).dot(Eigen::Vector3d(w[0], w[1], w[2]));
    return {forward - turn / 2, forward + turn / 2};
  }
  const double radius = r.desc.wheels.radius_m;
  return {radius * (dJointGetHingeAngleRate(r.hinges[0]) + dJointGetHingeAngleRate(r.hinges[2])) / 2,
          radius * (dJointGetHingeAngleRate(r.hinges[1]) + dJointGetHingeAngleRate(r.hinges[3])) / 2};
}

void Simulation::Impl::update_sensors(Robot& r) {
  const auto [left, right] = side_speeds_mps(r);
  r.odometry->update(left, right, kStepS);
  const Eigen::Isometry3d T = T_world_base(r);
  const dReal* v = dBodyGetLinearVel(r.chassis);
  const dReal* w = dBodyGetAngularVel(r.chassis);
  r.imu->update(T.linear(), Eigen::Vector3d(v[0], v[1], v[2]),
                T.linear().transpose() * Eigen::Vector3d(w[0], w[1], w[2]), kStepS);
}

Eigen::Isometry3d Simulation::T_world_base(std::size_t robot) const {
  return Impl::T_world_base(*impl_->robots[std::min(robot, impl_->robots.size() - 1)]);
}

std::optional<Eigen::Isometry3d> Simulation::T_world_camera(const std::string& camera, std::size_t robot) const {
  if (robot >= impl_->robots.size()) return std::nullopt;
  const auto& r = *impl_->robots[robot];
  for (const auto& c : r.desc.sensors.cameras)
    if (c.name == camera) return Impl::T_world_base(r) * c.mount.T_base_mount();
  return std::nullopt;
}

double Simulation::cast_ray_m(const Eigen::Vector3d& origin_world, const Eigen::Vector3d& direction_world,
                              double max_range_m, std::size_t own_robot) const {
  return impl_->cast_ray_m(origin_world, direction_world, max_range_m, own_robot);
}

}  // namespace rise::sim
