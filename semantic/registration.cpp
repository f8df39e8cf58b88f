#include "semantic/registration.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "semantic/voxel_grid.hpp"

namespace rise::semantic {
namespace {

// The voxel sizes of a cloud, from one look at it: thinned to a 4000th of
// its bounding box first (the same counts for any voxel above that, at a
// fraction of the cost), then bisected for a number of points.
class Sizing {
 public:
  explicit Sizing(const Cloud& cloud) {
    Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), hi = -lo;
    for (const auto& p : cloud.points)
      if (p.allFinite()) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
    box_m_ = lo.x() <= hi.x() ? static_cast<double>((hi - lo).norm()) : 0.0;
    if (box_m_ > 0.0) thin_ = voxel_filter(cloud, box_m_ / 4000.0);
  }

  // The voxel at which the cloud keeps about `points` points: a voxel
  // grid's occupied cells fall monotonically (near enough) as its cells grow.
  double voxel_for_points(size_t points) const {
    if (!(box_m_ > 0.0)) return 1e-3;
    double small = box_m_ / 4000.0, large = box_m_;
    if (thin_.size() <= points) return small;
    for (int i = 0; i < 24 && large / small > 1.05; ++i) {
      const double mid = std::sqrt(small * large);
      (VoxelGrid::count_cells(thin_.points, static_cast<float>(mid)) > points ? small : large) = mid;
    }
    return large;
  }

 private:
  double box_m_ = 0.0;
  Cloud thin_;
};

// The median distance from a point to its nearest other point, over a
// sample: the cloud's resolution. `cell_m`: a grid cell holding a few points.
double point_spacing(const Cloud& cloud, double cell_m) {
  const VoxelGrid grid(cloud.points, static_cast<float>(cell_m));
  const size_t step = std::max<size_t>(1, cloud.size() / 2000);
  std::vector<float> d;
  std::vector<VoxelGrid::Neighbour> nbs;
  for (size_t i = 0; i < cloud.size(); i += step) {
    grid.k_nearest(cloud.points[i], 2, nbs);
    if (nbs.size() == 2) d.push_back(std::sqrt(nbs[1].distance2_m2));
  }
  if (d.empty()) return grid.cell_m();
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return d[d.size() / 2];
}

void validate(const Cloud& source, const Cloud& target, const RegistrationSettings& s) {
  if (source.empty()) throw std::invalid_argument("register: source cloud is empty");
  if (target.empty()) throw std::invalid_argument("register: target cloud is empty");
  if (!(s.fine_voxel_m >= 0.0) || !(s.coarse_voxel_m >= 0.0) || !std::isfinite(s.fine_voxel_m) ||
      !std::isfinite(s.coarse_voxel_m))
    throw std::invalid_argument("register: voxels must be finite and >= 0");
  if (!(s.pairing_voxels >= 1.0)) throw std::invalid_argument("register: pairing_voxels must be at least 1");
  if (s.iterations_per_level < 1) throw std::invalid_argument("register: iterations_per_level must be at least 1");
  if (!(s.min_inlier_ratio >= 0.0 && s.min_inlier_ratio <= 1.0))
    throw std::invalid_argument("register: min_inlier_ratio must be in 0..1");
}

// Two answers of one level differ by more than ten times its convergence
// steps (a tenth of its voxel): not the same minimum.
bool apart(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, const IcpSettings& level) {
  const Eigen::Isometry3d d = a.inverse() * b;
  return d.translation().norm() > 10.0 * level.translation_epsilon_m ||
         Eigen::AngleAxisd(d.linear()).angle() > 10.0 * level.rotation_epsilon_rad;
}

}  // namespace

std::string icp_failure(const IcpResult& r, double min_inlier_ratio) {
  char why[160] = "";
  if (r.inlier_ratio < min_inlier_ratio)
    std::snprintf(why, sizeof why, "the clouds did not meet: %.0f %% of the source paired, %.0f %% needed",
                  100.0 * r.inlier_ratio, 100.0 * min_inlier_ratio);
  else if (!r.converged)
    std::snprintf(why, sizeof why, "ICP did not converge: still moving after %d iterations", r.iterations);
  return why;
}

std::vector<double> registration_voxels(const Cloud& source, const Cloud& target, const RegistrationSettings& s) {
  validate(source, target, s);
  const Sizing sizing(target);
  double fine = s.fine_voxel_m;
  if (fine == 0.0)
    fine = std::max(point_spacing(target, sizing.voxel_for_points(target.size() / 4 + 1)),
                    sizing.voxel_for_points(s.fine_points));
  double coarse = s.coarse_voxel_m;
  // At least three levels: a cloud of a few hundred points (PCL's bunny)
  // would otherwise be one level pairing within 2 cm, whose basin a 20°
  // start misses (35° off, "converged").
  if (coarse == 0.0) coarse = std::max(sizing.voxel_for_points(s.coarse_points), 4.0 * fine);
  if (!(fine > 0.0)) fine = 1e-3;
  coarse = std::max(coarse, fine);
  // Levels about a factor of two apart, ending exactly at the fine voxel.
  const int steps = static_cast<int>(std::ceil(std::log2(coarse / fine) - 1e-9));
  std::vector<double> voxels;
  for (int i = steps; i >= 0; --i) voxels.push_back(steps == 0 ? fine : fine * std::pow(coarse / fine, double(i) / steps));
  return voxels;
}

RegistrationResult register_clouds(const Cloud& source, const Cloud& target, const Eigen::Isometry3d& T_initial,
                                   const RegistrationSettings& s) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto seconds_since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  const std::vector<double> voxels = registration_voxels(source, target, s);
  struct Level {
    Cloud source, target;
    IcpSettings icp;
  };
  std::vector<Level> levels(voxels.size());
  double radius = 0.0;  // how far a rotation carries the source's points: their spread about the centroid
  const Cloud fine_source = voxel_filter(source, voxels.back());
  Cloud fine_target = voxel_filter(target, voxels.back());
  // The target's normals once, at the finest level; a coarser level's are
  // the mean of the fine ones in each of its voxels (voxel_filter), not a
  // new PCA per level: that cost more than all the levels' ICP together,
  // and moved no answer by more than 0.0005° on the real pairs.
  if (s.fine_metric == IcpMetric::PointToPlane || s.coarse_metric == IcpMetric::PointToPlane)
    estimate_normals(fine_target, s.normals_k, Eigen::Vector3f::Zero(), s.threads);
  for (size_t l = 0; l < voxels.size(); ++l) {
    const double v = voxels[l];
    const bool finest = l + 1 == voxels.size();
    Level& level = levels[l];
    // Coarse levels filter the finest level's points, a fraction of the
    // input (centroids of centroids: within a fine voxel of the same).
    level.source = finest ? fine_source : voxel_filter(fine_source, v);
    level.target = finest ? fine_target : voxel_filter(fine_target, v);
    IcpSettings& icp_settings = level.icp;
    icp_settings.metric = finest ? s.fine_metric : s.coarse_metric;
    if (l == 0) {
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      for (const auto& p : level.source.points) centroid += p.cast<double>();
      centroid /= static_cast<double>(level.source.size());
      for (const auto& p : level.source.points) radius += (p.cast<double>() - centroid).squaredNorm();
      radius = std::sqrt(radius / static_cast<double>(level.source.size()));
    }
    icp_settings.max_iterations = finest ? s.fine_iterations : s.iterations_per_level;
    icp_settings.max_correspondence_m = icp_settings.min_correspondence_m =
        (l == 0 ? s.coarse_pairing_voxels : s.pairing_voxels) * v;
    icp_settings.huber_m = v;
    icp_settings.threads = s.threads;
    icp_settings.coarse_stride = 1;
    // Converged once an update moves the cloud's points by less than a
    // hundredth of the voxel: finer steps are below what the level resolves.
    icp_settings.translation_epsilon_m = s.convergence_voxels * v;
    icp_settings.rotation_epsilon_rad = s.convergence_voxels * v / std::max(radius, v);
  }

  const double prepare_s = seconds_since(t0);

  // Levels [first, end) from T, appended to r.
  const auto run = [&](size_t first, size_t end, Eigen::Isometry3d T, RegistrationResult& r) {
    for (size_t l = first; l < end; ++l) {
      const Level& level = levels[l];
      RegistrationLevel done;
      done.voxel_m = voxels[l];
      done.pairing_m = level.icp.max_correspondence_m;
      done.source_points = level.source.size();
      done.target_points = level.target.size();
      const auto t = std::chrono::steady_clock::now();
      done.icp = icp(level.source, level.target, T, level.icp);
      done.seconds = seconds_since(t);
      T = done.icp.T_target_source;
      r.iterations += done.icp.iterations;
      r.levels.push_back(done);
    }
    r.T_target_source = T;
    r.rmse_m = r.levels.back().icp.rmse_m;
    r.inlier_ratio = r.levels.back().icp.inlier_ratio;
  };
  RegistrationResult result;
  run(0, levels.size(), T_initial, result);
  // A coarse level sees a street or a corridor as a few slabs and may slide
  // along it, out of a start that was already right (the 3DTK scans from
  // their odometry: 1.7 m along the street). So the finer half of the
  // pyramid also runs from the start itself, and the answer that pairs more
  // of the source at the finest level wins. Where the start's run settles
  // at the middle level where the whole pyramid's did (within a tenth of
  // that level's voxel), the finer levels would only repeat the same steps:
  // they run once.
  if (levels.size() > 2) {
    const size_t mid = levels.size() / 2;
    RegistrationResult refined;
    run(mid, mid + 1, T_initial, refined);
    if (apart(refined.T_target_source, result.levels[mid].icp.T_target_source, levels[mid].icp)) {
      run(mid + 1, levels.size(), refined.T_target_source, refined);
      if (refined.inlier_ratio > result.inlier_ratio) {
        refined.iterations += result.iterations;
        refined.from_start = true;
        result = std::move(refined);
      } else {
        result.iterations += refined.iterations;
      }
    } else {
      result.iterations += refined.iterations;
    }
  }
  result.prepare_s = prepare_s;
  result.total_s = seconds_since(t0);
  const IcpResult& last = result.levels.back().icp;
  result.failure = icp_failure(last, s.min_inlier_ratio);
  if (!result.failure.empty() && last.inlier_ratio >= s.min_inlier_ratio) {
    char level[48];
    std::snprintf(level, sizeof level, " at the %.3g m level", result.levels.back().voxel_m);
    result.failure += level;
  }
  result.converged = result.failure.empty();
  return result;
}

}  // namespace rise::semantic
