#pragma once

// Registering two clouds from their defaults: a coarse-to-fine voxel
// pyramid over icp() (icp.hpp), sized from the clouds themselves, so that
// a real indoor or outdoor pair (a room at 2 cm, a street at 20 cm, a
// bunny at 2 mm) needs no tuning, and a verdict that says when the answer
// cannot be trusted instead of returning it as if it could.
//
// Each level voxel-filters both clouds at its voxel (the target's normals
// estimated once at the finest level, averaged per voxel), pairs at most
// `source_points` of the source within `pairing_voxels` voxels with a
// Huber kernel one voxel wide, and hands its pose to the next, finer level.
// The coarsest level sees the whole scene in a few hundred points and
// pairs within metres: it brings 20° and a metre of initial error into the
// basin of the finer ones; the finest decides the accuracy.

#include <string>
#include <vector>

#include "semantic/cloud.hpp"
#include "semantic/icp.hpp"

namespace rise::semantic {

struct RegistrationSettings {
  /// Every level pairs point to plane by default: it slides along walls
  /// and ground into place in a few iterations, where point to point
  /// creeps along a scene's weak direction (a street's length).
  IcpMetric coarse_metric = IcpMetric::PointToPlane;
  IcpMetric fine_metric = IcpMetric::PointToPlane;
  /// The finest level's voxel; 0: the one that keeps fine_points of the
  /// target, or fine_spacing_share of the target's point spacing if that is
  /// larger (a cloud of fewer points keeps nearly all of them: a voxel of
  /// half the spacing merges only points closer than usual).
  double fine_voxel_m = 0.0;
  /// The finest voxel of a cloud under fine_points, as a share of its
  /// median point spacing (finite, > 0; used where fine_voxel_m is 0).
  double fine_spacing_share = 0.5;
  /// The coarsest level's voxel; 0: the one that keeps coarse_points of the
  /// target, and at least 4 fine voxels and, where the fine voxel is sized
  /// here (fine_voxel_m 0), 4 point spacings.
  double coarse_voxel_m = 0.0;
  size_t fine_points = 40000;
  size_t coarse_points = 1500;
  /// Each level pairs at most this many source points, evenly spread over
  /// its voxel-filtered source (0: all). The target's resolution decides
  /// the accuracy, not the number of pairs: on the real pairs 5000 points
  /// land within 0.02° and 3 mm of all 43k, at a fraction of the cost.
  size_t source_points = 5000;
  double pairing_voxels = 3.0;         ///< a level pairs points within this many of its voxels ...
  double coarse_pairing_voxels = 3.0;  ///< ... the coarsest within this many
  int iterations_per_level = 50;
  /// Point to point converges slowly along a scene's weak direction (a
  /// street's length, a ground's slope): the finest level may take longer.
  int fine_iterations = 100;
  /// A level has converged when an update moves the source's points less
  /// than this many of its voxels.
  double convergence_voxels = 0.01;
  int normals_k = 12;              ///< point-to-plane: neighbours per target normal
  /// The start's own run (see register_clouds) runs only where the start
  /// pairs at least this share of the source that the whole pyramid's
  /// answer pairs at the middle level (a start that was already right
  /// pairs about as many), and goes on past that level only where it
  /// still does there. 0: always.
  double restart_min_share = 0.9;
  /// Below this share of the source paired at the finest level, the clouds
  /// did not meet: not converged.
  double min_inlier_ratio = 0.3;
  int threads = 0;                 ///< icp()'s; 0: OpenMP's default
};

/// One level of the pyramid as it ran.
struct RegistrationLevel {
  double voxel_m = 0.0;
  double pairing_m = 0.0;
  size_t source_points = 0, target_points = 0;
  IcpResult icp;
  double seconds = 0.0;  ///< its ICP
};

struct RegistrationResult {
  Eigen::Isometry3d T_target_source = Eigen::Isometry3d::Identity();  ///< maps source points onto the target
  /// The finest level converged (its last update below icp's epsilons) with
  /// at least min_inlier_ratio of the source paired.
  bool converged = false;
  double rmse_m = 0.0;        ///< the finest level's, over its pairs
  double inlier_ratio = 0.0;  ///< the finest level's
  int iterations = 0;         ///< over all levels and both runs
  std::vector<RegistrationLevel> levels;  ///< coarse to fine, of the answer's run
  /// The answer came from the finer half of the pyramid run from the start
  /// itself, not from the whole pyramid (see register_clouds).
  bool from_start = false;
  std::string failure;        ///< why not converged, one line; empty when converged
  double prepare_s = 0.0;     ///< sizing the pyramid, filtering each level, the target normals
  double total_s = 0.0;
};

/// Why an ICP result is no answer, in one line ("the clouds did not meet:
/// ...", "ICP did not converge: ..."); empty when it converged and paired
/// at least `min_inlier_ratio` of the source. register_clouds' verdict on
/// its finest level, and rise-semantic register's on a plain ICP.
std::string icp_failure(const IcpResult& result, double min_inlier_ratio);

/// The pyramid's voxels, coarse to fine, for these clouds and settings.
std::vector<double> registration_voxels(const Cloud& source, const Cloud& target, const RegistrationSettings& settings = {});

/// Registers `source` onto `target` from `T_initial` (target ← source).
/// Throws std::invalid_argument on empty clouds or bad settings. Never
/// prints; allocates.
RegistrationResult register_clouds(const Cloud& source, const Cloud& target, const Eigen::Isometry3d& T_initial,
                                   const RegistrationSettings& settings = {});

}  // namespace rise::semantic
