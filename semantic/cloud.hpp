#pragma once

// The semantic engine's one point-cloud type. Metres, right-handed, z up
// (readers of other conventions, e.g. 3DTK's left-handed y-up centimetres,
// convert on the way in).

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <optional>
#include <string>
#include <vector>

namespace rise::semantic {

struct Cloud {
  std::vector<Eigen::Vector3f> points;   ///< metres, in the cloud's own frame
  std::vector<Eigen::Vector3f> normals;  ///< empty, or one unit normal per point

  size_t size() const { return points.size(); }
  bool empty() const { return points.empty(); }
};

/// One scan of a sequence: its points in the sensor frame and, where the
/// file came with one, the pose the robot believed (odometry) or knew (the
/// simulator's true pose) when it took them.
struct Scan {
  std::string name;                                ///< file stem, e.g. "scan000"
  Cloud cloud;                                     ///< sensor frame
  std::optional<Eigen::Isometry3d> T_world_scan;   ///< initial guess, if any
};

/// The cloud with every point (and normal) mapped by T: p' = T p.
Cloud transformed(const Cloud& cloud, const Eigen::Isometry3d& T);

}  // namespace rise::semantic
