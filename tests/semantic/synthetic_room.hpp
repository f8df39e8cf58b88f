#pragma once

// A synthetic room for registration tests: the six faces of a 6 x 4 x 3 m
// box, a table-sized block and a pillar, sampled at random (fixed seed) so
// two samplings of the same room share no points.

#include <Eigen/Geometry>

#include <random>
#include <vector>

#include "semantic/cloud.hpp"

namespace rise::semantic::test {

inline Cloud synthetic_room(size_t points, unsigned seed, double noise_m = 0.0) {
  struct Box {
    Eigen::Vector3d lo, hi;
  };
  // The room (seen from inside), a block on the floor and a pillar.
  const Box boxes[] = {{{0, 0, 0}, {6, 4, 3}}, {{1.5, 1.0, 0}, {2.7, 1.8, 0.8}}, {{4.2, 2.6, 0}, {4.6, 3.0, 3}}};
  std::vector<std::pair<double, std::pair<int, int>>> faces;  // area, (box, face)
  double total = 0.0;
  for (int b = 0; b < 3; ++b) {
    const Eigen::Vector3d e = boxes[b].hi - boxes[b].lo;
    for (int f = 0; f < 6; ++f) {
      const int axis = f / 2;
      const double area = e[(axis + 1) % 3] * e[(axis + 2) % 3];
      faces.push_back({area, {b, f}});
      total += area;
    }
  }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g(0.0, noise_m > 0.0 ? noise_m : 1.0);
  Cloud c;
  c.points.reserve(points);
  while (c.points.size() < points) {
    double pick = u(rng) * total;
    size_t k = 0;
    while (k + 1 < faces.size() && pick > faces[k].first) pick -= faces[k++].first;
    const auto [b, f] = faces[k].second;
    const int axis = f / 2;
    Eigen::Vector3d p;
    for (int i = 0; i < 3; ++i) p[i] = boxes[b].lo[i] + u(rng) * (boxes[b].hi[i] - boxes[b].lo[i]);
    p[axis] = (f % 2 == 0) ? boxes[b].lo[axis] : boxes[b].hi[axis];
    if (noise_m > 0.0) p[axis] += g(rng);
    c.points.push_back(p.cast<float>());
  }
  return c;
}

inline Eigen::Isometry3d pose(double yaw_deg, double pitch_deg, double roll_deg, const Eigen::Vector3d& t) {
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw_deg * kDeg, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(pitch_deg * kDeg, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll_deg * kDeg, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = t;
  return T;
}

inline double rotation_error_deg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() * 180.0 / 3.14159265358979323846;
}

inline double translation_error_m(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm();
}

}  // namespace rise::semantic::test
