#pragma once

// What the benchmarks that run PCL and Open3D beside ours share: the
// clouds in each library's type, a 4x4 back to an isometry, and timing.

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <chrono>
#include <functional>
#include <open3d/geometry/PointCloud.h>
#include <vector>

#include "semantic/cloud.hpp"

namespace rise::bench {

inline pcl::PointCloud<pcl::PointXYZ>::Ptr to_pcl(const semantic::Cloud& c) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr out(new pcl::PointCloud<pcl::PointXYZ>);
  out->points.reserve(c.size());
  for (const auto& p : c.points) out->points.emplace_back(p.x(), p.y(), p.z());
  out->width = static_cast<uint32_t>(c.size());
  out->height = 1;
  return out;
}

/// The points, and the normals when the cloud has them.
inline open3d::geometry::PointCloud to_open3d(const semantic::Cloud& c) {
  open3d::geometry::PointCloud out;
  out.points_.reserve(c.size());
  for (const auto& p : c.points) out.points_.push_back(p.cast<double>());
  for (const auto& n : c.normals) out.normals_.push_back(n.cast<double>());
  return out;
}

/// A 4x4 rigid transform, its rotation orthonormalised (the libraries'
/// float matrices, published matrices rounded to four digits).
inline Eigen::Isometry3d iso(const Eigen::Matrix4d& M) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(Eigen::Matrix3d(M.topLeftCorner<3, 3>())).normalized().toRotationMatrix();
  T.translation() = M.topRightCorner<3, 1>();
  return T;
}

inline double now_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// Runs `f` `n` times; its last answer in `out`, the fastest run's ms
/// returned: on a shared machine the slower runs measure the neighbours.
template <class T>
double time_fastest(int n, const std::function<T()>& f, T& out) {
  std::vector<double> ms;
  for (int i = 0; i < n; ++i) {
    const double t0 = now_ms();
    out = f();
    ms.push_back(now_ms() - t0);
  }
  return *std::min_element(ms.begin(), ms.end());
}

}  // namespace rise::bench
