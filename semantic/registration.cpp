#include "semantic/registration.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <functional>
#include <limits>
#include <memory>
#include <stdexcept>

#include "semantic/voxel_grid.hpp"

namespace rise::semantic {
namespace {

// The voxel sizes of a cloud, from a few counts of its occupied cells.
class Sizing {
 public:
  explicit Sizing(const Cloud& cloud) : points_(cloud.points) {
    Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), hi = -lo;
    for (const auto& p : cloud.points)
      if (p.allFinite()) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
        ++finite_;
      }
    box_m_ = lo.x() <= hi.x() ? static_cast<double>((hi - lo).norm()) : 0.0;
  }

  // The voxel at which the cloud keeps about `points` points, between a
  // 4000th of its bounding box and all of it. A voxel grid's occupied cells
  // fall monotonically (near enough) as its cells grow, and nearly as a
  // power of the cell (a surface's as its square): so the search
  // interpolates in log-log between a voxel that keeps too many and one
  // that keeps few enough (regula falsi, Illinois' variant), three to five
  // counts where bisection took eight.
  double voxel_for_points(size_t points) const {
    if (!(box_m_ > 0.0)) return 1e-3;
    double small = box_m_ / 4000.0, large = box_m_;
    if (finite_ <= points) return small;
    const double want = std::log(static_cast<double>(points));
    double f_small = std::log(static_cast<double>(finite_)) - want;  // at most all points: > 0, too many
    double f_large = -want;                                          // one cell: <= 0
    int kept_side = 0;  // which end the last two steps kept (Illinois: halve its value when it repeats)
    for (int i = 0; i < 24 && large / small > 1.05; ++i) {
      const double ls = std::log(small), ll = std::log(large);
      // The first guess: a surface's count falls as the square of the voxel
      // from all points at the smallest (the ends' straight line is too flat
      // where few points share a cell).
      double mid = i == 0 ? small * std::sqrt(std::exp(f_small)) : std::exp(ls + (ll - ls) * f_small / (f_small - f_large));
      // Stay inside the bracket: at least a twentieth of it from either end.
      mid = std::clamp(mid, std::exp(ls + 0.05 * (ll - ls)), std::exp(ll - 0.05 * (ll - ls)));
      // Past `points` the count stops: the whole cloud's, extrapolated
      // from the share read, is near enough to aim the next step.
      size_t read = 0;
      const size_t count = VoxelGrid::count_cells(points_, static_cast<float>(mid), points, &read);
      const double estimate = count > points ? static_cast<double>(count) * static_cast<double>(points_.size()) /
                                                   static_cast<double>(std::max<size_t>(read, 1))
                                             : static_cast<double>(std::max<size_t>(count, 1));
      const double f = std::log(estimate) - want;
      if (count > points) {
        small = mid;
        f_small = f;
        if (kept_side == 1) f_large *= 0.5;
        kept_side = 1;
      } else {
        large = mid;
        f_large = f;
        if (kept_side == -1) f_small *= 0.5;
        kept_side = -1;
        if (count * 100 >= points * 97) break;  // within 3 % below: near enough
      }
    }
    return large;
  }

 private:
  const std::vector<Eigen::Vector3f>& points_;
  size_t finite_ = 0;
  double box_m_ = 0.0;
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

constexpr size_t kCellNormalsFrom = 10000;  // target points at the finest level

// At most `count` of the cloud's points (all for 0), every k-th in its
// order: a voxel filter's output keeps its cells' first-seen order, so a
// scan's sweep is sampled along its whole length.
Cloud evenly_spread(Cloud cloud, size_t count) {
  const size_t n = cloud.size();
  if (count == 0 || n <= count) return cloud;
  const bool normals = cloud.normals.size() == n;
  Cloud out;
  out.points.reserve(count);
  for (size_t i = 0; i < count; ++i) {
    out.points.push_back(cloud.points[i * n / count]);
    if (normals) out.normals.push_back(cloud.normals[i * n / count]);
  }
  return out;
}

void validate(const Cloud& source, const Cloud& target, const RegistrationSettings& s) {
  if (source.empty()) throw std::invalid_argument("register: source cloud is empty");
  if (target.empty()) throw std::invalid_argument("register: target cloud is empty");
  if (!(s.fine_voxel_m >= 0.0) || !(s.coarse_voxel_m >= 0.0) || !std::isfinite(s.fine_voxel_m) ||
      !std::isfinite(s.coarse_voxel_m))
    throw std::invalid_argument("register: voxels must be finite and >= 0");
  if (!(s.fine_spacing_share > 0.0) || !std::isfinite(s.fine_spacing_share))
    throw std::invalid_argument("register: fine_spacing_share must be finite and > 0");
  if (!(s.pairing_voxels >= 1.0)) throw std::invalid_argument("register: pairing_voxels must be at least 1");
  if (s.iterations_per_level < 1) throw std::invalid_argument("register: iterations_per_level must be at least 1");
  if (!(s.min_inlier_ratio >= 0.0 && s.min_inlier_ratio <= 1.0))
    throw std::invalid_argument("register: min_inlier_ratio must be in 0..1");
  if (!(s.restart_min_share >= 0.0 && s.restart_min_share <= 1.0))
    throw std::invalid_argument("register: restart_min_share must be in 0..1");
}

// Two answers of one level differ by more than ten times its convergence
// steps (a tenth of its voxel): not the same minimum.
bool apart(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, const IcpSettings& level) {
  const Eigen::Isometry3d d = a.inverse() * b;
  return d.translation().norm() > 10.0 * level.translation_epsilon_m ||
         Eigen::AngleAxisd(d.linear()).angle() > 10.0 * level.rotation_epsilon_rad;
}

// Two jobs side by side where there are two threads (source and target,
// the sizing's two searches); what one throws is thrown here, after the
// parallel region.
void side_by_side(int threads, const std::function<void()>& a, const std::function<void()>& b) {
  std::exception_ptr errors[2];
#pragma omp parallel for num_threads(threads)
  for (int i = 0; i < 2; ++i) {
    try {
      (i == 0 ? a : b)();
    } catch (...) {
      errors[i] = std::current_exception();
    }
  }
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
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
  double fine = s.fine_voxel_m, coarse = s.coarse_voxel_m, coarse_by_count = 0.0, spacing = 0.0;
  // The fine voxel and the spacing beside the coarse voxel's search (the
  // room's 112k points: 7.7 -> 7.4 ms, the median of 15).
  side_by_side(
      s.threads == 1 ? 1 : 2,
      [&] {
        if (fine != 0.0) return;
        const double by_count = sizing.voxel_for_points(s.fine_points);
        // The spacing's grid wants cells of about four points. Where
        // by_count merges points (the cloud has more than fine_points),
        // scale it (a surface's cells hold points as the square of their
        // size); else search for it.
        const double n = static_cast<double>(target.size());
        const double cell = n > static_cast<double>(s.fine_points)
                                ? by_count * std::sqrt(4.0 * static_cast<double>(s.fine_points) / n)
                                : sizing.voxel_for_points(target.size() / 4 + 1);
        // A cloud of fewer points keeps them all: a voxel at the spacing
        // itself merges neighbours (PCL's bunny, 397 -> 368 points, 2.1°
        // from the Stanford repository's registration of the two scans;
        // with every point 0.65°).
        spacing = point_spacing(target, cell);
        fine = std::max(spacing * s.fine_spacing_share, by_count);
      },
      [&] {
        if (coarse == 0.0) coarse_by_count = sizing.voxel_for_points(s.coarse_points);
      });
  // At least three levels, the coarsest 4 point spacings at least: a cloud
  // of a few hundred points (PCL's bunny) would otherwise be one level
  // pairing within 2 cm, whose basin a 20° start misses (35° off, "converged").
  if (coarse == 0.0) coarse = std::max(coarse_by_count, 4.0 * std::max(fine, spacing));
  if (!(fine > 0.0)) fine = 1e-3;
  coarse = std::max(coarse, fine);
  // Levels about a factor of two apart, ending exactly at the fine voxel.
  const int steps = static_cast<int>(std::ceil(std::log2(coarse / fine) - 1e-9));
  std::vector<double> voxels;
  for (int i = steps; i >= 0; --i) voxels.push_back(steps == 0 ? fine : fine * std::pow(coarse / fine, double(i) / steps));
  return voxels;
}

namespace {

// One level of the pyramid: its clouds, its ICP settings and, once
// prepared, its target's grids.
struct Level {
  double voxel_m = 0.0;
  Cloud source, target;
  IcpSettings icp;
  std::unique_ptr<IcpTarget> prepared;
};

// The finest level's clouds, filtered, with the target's normals; each
// coarser level filters the next finer one's points, a fraction of the
// input (centroids of centroids: within a finer voxel of the same).
std::vector<Level> filter_levels(const Cloud& source, const Cloud& target, const std::vector<double>& voxels,
                                 const RegistrationSettings& s, int pair_threads) {
  std::vector<Level> levels(voxels.size());
  for (size_t l = 0; l < voxels.size(); ++l) levels[l].voxel_m = voxels[l];
  Cloud& fine_source = levels.back().source;
  Cloud& fine_target = levels.back().target;
  side_by_side(pair_threads, [&] { fine_source = voxel_filter(source, voxels.back()); },
               [&] { fine_target = voxel_filter(target, voxels.back()); });
  // The target's normals once, at the finest level; a coarser level's are
  // the mean of the fine ones in each of its voxels (voxel_filter), not a
  // new PCA per level: that cost more than all the levels' ICP together,
  // and moved no answer by more than 0.0005° on the real pairs.
  if (s.fine_metric == IcpMetric::PointToPlane || s.coarse_metric == IcpMetric::PointToPlane) {
    // A scene's normals from cell moments (a fifteenth of the k-nearest
    // search's cost: 42-46 -> 2.3-3.3 ms on the real pairs' 40k points, 2
    // threads; their answers moved by at most 0.2°, all still within
    // 0.33° and 1.8 cm of the references); a small cloud's from its k
    // nearest, where they cost little and the cells' blocks would span
    // much of the object (PCL's bunny then did not converge).
    if (fine_target.size() >= kCellNormalsFrom)
      estimate_normals_cells(fine_target, s.normals_k, Eigen::Vector3f::Zero(), s.threads);
    else
      estimate_normals(fine_target, s.normals_k, Eigen::Vector3f::Zero(), s.threads);
  }
  side_by_side(
      pair_threads,
      [&] {
        for (size_t l = voxels.size() - 1; l-- > 0;) levels[l].source = voxel_filter(levels[l + 1].source, voxels[l]);
      },
      [&] {
        for (size_t l = voxels.size() - 1; l-- > 0;) levels[l].target = voxel_filter(levels[l + 1].target, voxels[l]);
      });
  return levels;
}

// How far a rotation carries the cloud's points: their spread about the
// centroid.
double spread_m(const Cloud& cloud) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : cloud.points) centroid += p.cast<double>();
  centroid /= static_cast<double>(cloud.size());
  double sum = 0.0;
  for (const auto& p : cloud.points) sum += (p.cast<double>() - centroid).squaredNorm();
  return std::sqrt(sum / static_cast<double>(cloud.size()));
}

// Each level's ICP settings, and its source thinned to s.source_points.
void configure_levels(std::vector<Level>& levels, const RegistrationSettings& s) {
  const double radius = spread_m(levels.front().source);
  for (size_t l = 0; l < levels.size(); ++l) {
    const double v = levels[l].voxel_m;
    const bool finest = l + 1 == levels.size();
    Level& level = levels[l];
    IcpSettings& icp_settings = level.icp;
    icp_settings.metric = finest ? s.fine_metric : s.coarse_metric;
    level.source = evenly_spread(std::move(level.source), s.source_points);
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
}

// Each level's target grids, once for both runs of register_clouds, side
// by side (the finest, largest first). An error is thrown here, not inside
// the parallel loop.
void prepare_targets(std::vector<Level>& levels, int pair_threads) {
  std::vector<std::exception_ptr> errors(levels.size());
  const auto n_levels = static_cast<std::ptrdiff_t>(levels.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(pair_threads)
  for (std::ptrdiff_t k = 0; k < n_levels; ++k) {
    const auto l = static_cast<size_t>(n_levels - 1 - k);
    try {
      levels[l].prepared = std::make_unique<IcpTarget>(levels[l].target, levels[l].icp);
    } catch (...) {
      errors[l] = std::current_exception();
    }
  }
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
}

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// Levels [first, end) from T, appended to r; each stops early where `stop` holds (icp()).
void run_levels(const std::vector<Level>& levels, size_t first, size_t end, Eigen::Isometry3d T,
                RegistrationResult& r, const std::function<bool(const Eigen::Isometry3d&, const IcpResult&)>& stop = {}) {
  for (size_t l = first; l < end; ++l) {
    const Level& level = levels[l];
    RegistrationLevel done;
    done.voxel_m = level.voxel_m;
    done.pairing_m = level.icp.max_correspondence_m;
    done.source_points = level.source.size();
    done.target_points = level.target.size();
    const auto t = std::chrono::steady_clock::now();
    done.icp = icp(level.source, *level.prepared, T, stop);
    done.seconds = seconds_since(t);
    T = done.icp.T_target_source;
    r.iterations += done.icp.iterations;
    r.levels.push_back(done);
  }
  r.T_target_source = T;
  r.rmse_m = r.levels.back().icp.rmse_m;
  r.inlier_ratio = r.levels.back().icp.inlier_ratio;
}

}  // namespace

RegistrationResult register_clouds(const Cloud& source, const Cloud& target, const Eigen::Isometry3d& T_initial,
                                   const RegistrationSettings& s) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<double> voxels = registration_voxels(source, target, s);
  const int pair_threads = s.threads == 1 ? 1 : 2;
  std::vector<Level> levels = filter_levels(source, target, voxels, s, pair_threads);
  configure_levels(levels, s);
  prepare_targets(levels, pair_threads);
  const double prepare_s = seconds_since(t0);

  RegistrationResult result;
  run_levels(levels, 0, levels.size(), T_initial, result);
  // A coarse level sees a street or a corridor as a few slabs and may slide
  // along it, out of a start that was already right (the 3DTK scans from
  // their odometry: 1.7 m along the street). So the finer half of the
  // pyramid also runs from the start itself, and the answer that pairs more
  // of the source at the finest level wins. It stops early (icp()'s stop):
  // at once where the start pairs clearly fewer of the source at the
  // middle level than the whole pyramid's answer there (restart_min_share:
  // it was not already right; the room's scans from the tutorial's guess,
  // 53 % against 81 %, 9.5 ms of 16 iterations saved), and as soon as it
  // comes within a tenth of that level's voxel of that answer (the finer
  // levels would only repeat the same steps: they run once).
  if (levels.size() > 2) {
    const size_t mid = levels.size() / 2;
    RegistrationResult refined;
    const Eigen::Isometry3d& settled = result.levels[mid].icp.T_target_source;
    const double enough = s.restart_min_share * result.levels[mid].icp.inlier_ratio;
    run_levels(levels, mid, mid + 1, T_initial, refined, [&](const Eigen::Isometry3d& T, const IcpResult& so_far) {
      return (so_far.iterations == 1 && so_far.inlier_ratio < enough) || !apart(T, settled, levels[mid].icp);
    });
    if (apart(refined.T_target_source, settled, levels[mid].icp) && refined.inlier_ratio >= enough) {
      run_levels(levels, mid + 1, levels.size(), refined.T_target_source, refined);
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
