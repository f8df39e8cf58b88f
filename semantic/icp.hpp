#pragma once

// Iterative closest point, as in the seed paper's data registration (section
// 3): nearest neighbours from a regular voxel grid (the paper's bucket
// structure), a maximum correspondence distance that shrinks over the
// iterations, parallel over points with a parallel reduction.

#include "semantic/cloud.hpp"

#include <functional>
#include <memory>
#include <vector>

namespace rise::semantic {

enum class IcpMetric { PointToPoint, PointToPlane };

struct IcpSettings {
  IcpMetric metric = IcpMetric::PointToPoint;
  int max_iterations = 30;
  double max_correspondence_m = 0.5;   ///< first iteration's pairing distance
  double min_correspondence_m = 0.05;  ///< it shrinks towards this one
  double huber_m = 0.0;                ///< robust kernel width; 0: none
  double translation_epsilon_m = 1e-5; ///< converged when an update moves less ...
  double rotation_epsilon_rad = 1e-5;  ///< ... and turns less than these
  int threads = 0;                     ///< 0: OpenMP's default
  int max_points_per_cell = 0;         ///< grid cell lists capped at this many target points; 0: all
  /// false: a far pair (beyond the finest grid level, about the point
  /// spacing) is searched in a sample of at most 32 points per cell: much
  /// faster early on, the same answer once converged. true: every pair
  /// within min_correspondence_m is the exact nearest neighbour (PCL's and
  /// Open3D's k-d tree answer; iteration by iteration with coarse_stride 1).
  bool exact_neighbours = false;
  /// true: a source point whose last exact search found its nearest target
  /// point with the next one farther away than the distance it has moved
  /// since (plus its distance to it) keeps that pair without a search. The
  /// pairs, and so the result, are those searching would give, to the bit.
  bool reuse_pairs = true;
  /// The first half of the iterations (while the pairing distance
  /// shrinks) pairs only every coarse_stride-th source point, the rest all
  /// of them: Rusinkiewicz and Levoy's sampling of the source ("Efficient
  /// variants of the ICP algorithm", 2001). The early, far pairs cost the
  /// most to search and only have to point the right way; the last
  /// iterations, and so the result's accuracy, use every point. 1: every
  /// point in every iteration (PCL's and Open3D's ICP).
  int coarse_stride = 8;
};

struct IcpResult {
  Eigen::Isometry3d T_target_source = Eigen::Isometry3d::Identity();  ///< maps source points onto the target
  int iterations = 0;
  double rmse_m = 0.0;         ///< over the inlier pairs of the last iteration
  double inlier_ratio = 0.0;   ///< paired source points / all source points
  bool converged = false;
  bool stopped = false;  ///< ended by the caller's stop condition (see icp() below)
  /// The last update's translation and rotation: how far from settled a
  /// match that ran out of iterations still was.
  double last_step_m = 0.0;
  double last_step_rad = 0.0;
};

/// Registers `source` onto `target` from `T_initial` (target ← source).
/// PointToPlane needs target normals (estimate_normals below). Throws
/// std::invalid_argument on empty clouds or bad settings.
IcpResult icp(const Cloud& source, const Cloud& target, const Eigen::Isometry3d& T_initial,
              const IcpSettings& settings = {});

namespace detail {
class GridPyramid;
}

/// A target made ready for icp() with these settings: its nearest-neighbour
/// grids, built once for any number of sources and starts (and, for
/// different targets, in parallel). Keeps a reference to `target`, which
/// must outlive it. Throws as icp() does.
class IcpTarget {
 public:
  IcpTarget(const Cloud& target, const IcpSettings& settings);
  ~IcpTarget();
  IcpTarget(const IcpTarget&) = delete;
  IcpTarget& operator=(const IcpTarget&) = delete;
  const Cloud& cloud() const { return cloud_; }
  const IcpSettings& settings() const { return settings_; }

 private:
  friend IcpResult icp(const Cloud& source, const IcpTarget& target, const Eigen::Isometry3d& T_initial,
                       const std::function<bool(const Eigen::Isometry3d&, const IcpResult&)>& stop);
  const Cloud& cloud_;
  IcpSettings settings_;
  std::unique_ptr<detail::GridPyramid> pyramid_;
};

/// icp() onto a prepared target, with the settings it was prepared for.
IcpResult icp(const Cloud& source, const IcpTarget& target, const Eigen::Isometry3d& T_initial);

/// The same, stopping early (stopped = true, converged false) once
/// `stop` holds for the pose after an update and the result so far (its
/// iterations, and the rmse and inlier ratio of the pairs that update
/// came from): for a run that only has to show whether it reaches a known
/// answer, or pairs as much as one.
IcpResult icp(const Cloud& source, const IcpTarget& target, const Eigen::Isometry3d& T_initial,
              const std::function<bool(const Eigen::Isometry3d&, const IcpResult&)>& stop);

/// The pairing distance of each iteration: geometric from
/// max_correspondence_m down to min_correspondence_m over the first half of
/// max_iterations, then min_correspondence_m. ICP converges only once it
/// pairs at the minimum.
std::vector<double> correspondence_schedule(const IcpSettings& settings);

/// Unit normals from the k nearest neighbours' covariance (PCA), oriented
/// towards `viewpoint`; fills cloud.normals. `threads` 0: OpenMP's default.
void estimate_normals(Cloud& cloud, int k = 10, const Eigen::Vector3f& viewpoint = Eigen::Vector3f::Zero(),
                      int threads = 0);

/// estimate_normals at a fraction of the cost, for large clouds: cells of
/// about k / 2 points of a surface (as estimate_normals sizes them), each
/// cell's moments summed once, and one normal per cell from the moments of
/// its 3x3x3 block (about 13 k / 2 points of a surface, within one to two
/// cells) instead of a k-nearest search per point. Smoother than the k
/// nearest: on an object of a few hundred points the block spans much of it
/// (PCL's bunny: registration no longer converges), so keep it for scenes.
void estimate_normals_cells(Cloud& cloud, int k = 10, const Eigen::Vector3f& viewpoint = Eigen::Vector3f::Zero(),
                            int threads = 0);

/// One point per occupied cube of `leaf_m` (the centroid of its points).
Cloud voxel_filter(const Cloud& cloud, double leaf_m);

}  // namespace rise::semantic
