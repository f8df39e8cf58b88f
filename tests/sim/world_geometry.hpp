#pragma once

// The world file's solids as boxes, computed straight from the file's
// numbers (independently of the simulator's ODE geoms), to check ray-cast
// points against: walls (the pieces of sim::wall_boxes: lengthened by their
// thickness, split around door openings, sim/README.md), stair blocks,
// closed doors, static boxes, props, the ceiling slab and movable objects at
// their start. Shared by the scanner test and bench/scanner_throughput.cpp.

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "sim/world_description.hpp"

namespace rise::sim::testing {

struct Solid {
  std::string name;
  bool wall = false;
  Eigen::Vector3d center_m;
  Eigen::Vector3d half_m;
  double yaw_rad = 0.0;

  /// Signed distance to the surface: < 0 inside.
  double signed_distance_m(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d d = p - center_m;
    const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
    const Eigen::Vector3d local(c * d.x() + s * d.y(), -s * d.x() + c * d.y(), d.z());
    const Eigen::Vector3d q = local.cwiseAbs() - half_m;
    return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
  }
};

inline Solid box_solid(const BoxObstacle& b, bool wall) {
  return {b.name, wall, {b.center_m[0], b.center_m[1], b.center_m[2]},
          {b.size_m[0] / 2, b.size_m[1] / 2, b.size_m[2] / 2}, b.yaw_rad};
}

inline std::vector<Solid> world_solids(const WorldDescription& w) {
  std::vector<Solid> out;
  for (const auto& b : w.boxes) out.push_back(box_solid(b, false));
  for (const auto& p : w.props) out.push_back(box_solid(p.box, false));
  for (const auto& x : w.walls)
    for (const auto& b : wall_boxes(x)) out.push_back(box_solid(b, true));
  // The ceiling's points lie on the slab's underside, z = height_m.
  if (w.ceiling) out.push_back(box_solid(ceiling_box(*w.ceiling), false));
  for (const auto& s : w.stairs) {
    const double c = std::cos(s.yaw_rad), sn = std::sin(s.yaw_rad);
    for (int i = 0; i <= s.steps; ++i) {
      const bool landing = i == s.steps;
      const double length = landing ? s.landing_m : s.tread_m;
      const double height = landing ? s.landing_height_m() : (i + 1) * s.riser_m;
      const double along = i * s.tread_m + length / 2;
      out.push_back({s.name, false, {s.start_m[0] + c * along, s.start_m[1] + sn * along, height / 2},
                     {length / 2, s.width_m / 2, height / 2}, s.yaw_rad});
    }
  }
  for (const auto& d : w.doors) {
    const double c = std::cos(d.yaw_rad), sn = std::sin(d.yaw_rad);
    out.push_back({d.name, false, {d.hinge_m[0] + c * d.width_m / 2, d.hinge_m[1] + sn * d.width_m / 2,
                                   0.01 + d.height_m / 2},  // hangs 1 cm above the floor
                   {d.width_m / 2, d.thickness_m / 2, d.height_m / 2}, d.yaw_rad});
  }
  for (const auto& o : w.objects)
    out.push_back({o.name, false, {o.center_m[0], o.center_m[1], o.center_m[2]},
                   {o.size_m[0] / 2, o.size_m[1] / 2, o.size_m[2] / 2}, 0.0});
  return out;
}

/// The solid (or "ground", the plane z = 0) whose surface is nearest to p,
/// and that surface distance (m).
struct Nearest {
  std::string name;
  double distance_m = std::numeric_limits<double>::infinity();
};
inline Nearest nearest_surface(const std::vector<Solid>& solids, const Eigen::Vector3d& p) {
  Nearest n{"ground", std::fabs(p.z())};
  for (const auto& s : solids) {
    const double d = std::fabs(s.signed_distance_m(p));
    if (d < n.distance_m) n = {s.name, d};
  }
  return n;
}

}  // namespace rise::sim::testing
