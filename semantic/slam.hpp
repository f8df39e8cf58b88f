#pragma once

// 6D SLAM as in the seed paper (section 3) and Nüchter's slam6d: a) ICP
// alignment of each scan onto the ones before it, b) loop closing — scans
// whose centres come close again after a while are matched by ICP and the
// match kept when it is good, c) map relaxation — a pose graph of the
// sequential and loop matches relaxed with Ceres (pose_graph.hpp); then all
// scans merged into one map and voxel-filtered.

#include "semantic/cloud.hpp"
#include "semantic/icp.hpp"
#include "semantic/pose_graph.hpp"

#include <cstddef>
#include <functional>
#include <string_view>
#include <vector>

namespace rise::semantic {

/// Which earlier scans a scan is matched onto in the sequential step.
enum class SlamTarget {
  LastScans,     ///< the map_scans scans before it in the sequence
  NearestScans,  ///< the one before it and the map_scans-1 earlier ones nearest to where it is expected
};

struct SlamSettings {
  /// For the sequential and the loop matches; point-to-plane, as indoor
  /// scans are mostly planes (walls, floor, ceiling).
  IcpSettings icp = [] {
    IcpSettings s;
    s.metric = IcpMetric::PointToPlane;
    // Settled when an update moves less than 0.3 mm and turns less than
    // 0.02°: far below the 5 cm voxels matched, and reached in 30
    // iterations by every match of the test sequences (1e-5 was not, by
    // 14 of 58).
    s.translation_epsilon_m = 3e-4;
    s.rotation_epsilon_rad = 3e-4;
    return s;
  }();
  double scan_voxel_m = 0.05;       ///< each scan is voxel-filtered to this for matching; 0: not
  /// The scan being matched (ICP's source) is thinned further to this; what
  /// it is matched onto keeps scan_voxel_m. Fewer queries per iteration;
  /// a plane is pinned by far fewer points than a dense scan holds.
  /// ≤ scan_voxel_m: the source as filtered to scan_voxel_m.
  double source_voxel_m = 0.1;
  int normals_k = 10;               ///< neighbours per normal (point-to-plane ICP only)
  int map_scans = 3;                ///< scan i is matched onto this many earlier scans, merged ...
  SlamTarget target = SlamTarget::LastScans;  ///< ... chosen so
  /// A sequential match that did not converge, or paired less than this
  /// share of the scan, is refused: the scan keeps the odometry's pose and
  /// SlamResult::refused names it.
  double match_min_inlier_ratio = 0.1;
  double loop_radius_m = 3.0;       ///< candidate loop: scan centres at most this far apart ...
  int loop_min_separation = 4;      ///< ... and at least this many scans apart in the sequence
  int loop_max_per_scan = 2;        ///< the nearest candidates tried per scan
  double loop_max_rmse_m = 0.05;    ///< a loop match is kept when its rmse is at most this ...
  double loop_min_inlier_ratio = 0.4;  ///< ... and at least this share of points paired
  double information_sigma_min_m = 0.005;  ///< floor of the rmse used to weigh an edge
  int relaxation_rounds = 2;        ///< match the edges again from the relaxed poses, relax again
  /// Those later rounds' sequential matches start pairing at this distance
  /// (not icp.max_correspondence_m): relaxed poses are off by centimetres,
  /// not by the odometry's drift, and a narrow start converges in a few
  /// iterations. 0: as the first round.
  double refine_correspondence_m = 0.1;
  PoseGraphSettings graph;
  double map_voxel_m = 0.05;        ///< the merged map's voxel filter; 0: not filtered
};

/// A loop closed by an ICP match: scan `to` seen from scan `from`.
struct SlamLoop {
  std::size_t from = 0;
  std::size_t to = 0;
  Eigen::Isometry3d T_from_to = Eigen::Isometry3d::Identity();
  double rmse_m = 0.0;
  double inlier_ratio = 0.0;
};

/// Wall-clock seconds of each stage.
struct SlamTimings {
  double preprocess_s = 0.0;  ///< voxel filter (+ normals)
  double sequential_s = 0.0;
  double loops_s = 0.0;
  double relaxation_s = 0.0;
  double map_s = 0.0;
  double total_s = 0.0;
};

struct SlamResult {
  std::vector<Eigen::Isometry3d> T_world_scan;             ///< the final poses, scan 0 where its guess put it
  std::vector<Eigen::Isometry3d> T_world_scan_sequential;  ///< after sequential ICP alone
  std::vector<IcpResult> sequential;  ///< the match of scan i onto the ones before it (i ≥ 1; [0] empty)
  std::vector<std::size_t> refused;   ///< scans whose first sequential match was refused (match_min_inlier_ratio)
  std::vector<SlamLoop> loops;        ///< the loop matches kept (of the last round)
  int loop_candidates = 0;            ///< loop matches tried (last round)
  PoseGraphResult relaxation;         ///< the last relaxation's; no iterations when no loop was ever found
  SlamTimings timings;
  Cloud map;                          ///< all scans in the world frame, voxel-filtered
};

/// Called as work progresses: `done` of `total` steps of `stage`
/// ("preprocess", "sequential icp", "loop closing", "relaxation", "map").
using SlamProgress = std::function<void(std::size_t done, std::size_t total, std::string_view stage)>;

/// Registers the scans (sensor-frame clouds; T_world_scan the odometry
/// guess, or where absent the previous scan's pose) into one map. The first
/// scan's pose is kept: it fixes the map frame. Throws std::invalid_argument
/// for no scans, an empty scan (naming it) or bad settings. Allocates, runs
/// ICP in parallel as IcpSettings::threads says; never prints.
SlamResult slam(std::vector<Scan> scans, const SlamSettings& settings = {}, const SlamProgress& progress = {});

/// The information matrix of a point-to-point match of `source_points`
/// (source frame) with residual `sigma_m`: Σ Jᵀ·J / σ², J = [I, −[p]×],
/// the Gauss–Newton Hessian of the match, in the edge's (tx, ty, tz, rx, ry,
/// rz) order with the perturbation in the source frame (PoseGraphEdge).
Eigen::Matrix<double, 6, 6> match_information(const std::vector<Eigen::Vector3f>& source_points, double sigma_m,
                                              double weight = 1.0);

}  // namespace rise::semantic
