#include "semantic/cloud.hpp"

namespace rise::semantic {

Cloud transformed(const Cloud& cloud, const Eigen::Isometry3d& T) {
  const Eigen::Isometry3f Tf = T.cast<float>();
  Cloud out;
  out.points.reserve(cloud.points.size());
  for (const auto& p : cloud.points) out.points.push_back(Tf * p);
  out.normals.reserve(cloud.normals.size());
  for (const auto& n : cloud.normals) out.normals.push_back(Tf.linear() * n);
  return out;
}

}  // namespace rise::semantic
