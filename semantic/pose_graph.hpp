#pragma once

// Pose-graph relaxation: the seed paper's "map relaxation" step of 6D SLAM
// (section 3; Nüchter's slam6d relaxes its graph of scan poses once a loop
// is closed). Nodes are scan poses T_world_scan in SE(3), edges are measured
// relative poses with a 6×6 information matrix. Solved with Ceres, each pose
// a translation + unit quaternion on ProductManifold<R³, EigenQuaternion>;
// one node is held fixed (the gauge).

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <vector>

namespace rise::semantic {

/// A relative-pose measurement: where node `to` is in node `from`'s frame.
struct PoseGraphEdge {
  std::size_t from = 0;
  std::size_t to = 0;
  Eigen::Isometry3d T_from_to = Eigen::Isometry3d::Identity();
  /// Inverse covariance of the error log(T_from_to⁻¹ · T_from⁻¹ · T_to),
  /// ordered (tx, ty, tz in m; rx, ry, rz in rad, a rotation vector), the
  /// perturbation expressed in node `to`'s frame. Symmetric positive definite.
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Identity();
};

struct PoseGraph {
  std::vector<Eigen::Isometry3d> T_world_node;  ///< the initial guess, one per node
  std::vector<PoseGraphEdge> edges;
};

struct PoseGraphSettings {
  int max_iterations = 100;          ///< Levenberg–Marquardt iterations
  double function_tolerance = 1e-12; ///< Ceres' relative cost-change stop
  std::size_t fixed_node = 0;        ///< held at its initial pose
  int threads = 1;
  /// Start from chordal_initialization() instead of the graph's guess:
  /// from MIT's odometry Levenberg–Marquardt stops in a local minimum
  /// (cost 385 after 389 iterations; from the chordal guess 20.6 after 17,
  /// semantic/README.md "Pose graphs from files").
  bool chordal_initialization = true;
};

struct PoseGraphResult {
  std::vector<Eigen::Isometry3d> T_world_node;  ///< the relaxed poses
  int iterations = 0;
  double initial_cost = 0.0;  ///< ½ Σ rᵀ·Ω·r over the edges at the graph's guess, ...
  double start_cost = 0.0;    ///< ... where Levenberg–Marquardt started (the chordal guess, if chosen) ...
  double final_cost = 0.0;    ///< ... and after
  bool converged = false;     ///< Ceres stopped on a tolerance, not on the iteration limit
};

/// Relaxes the graph: the poses that best agree with all edges in the
/// information-weighted least-squares sense. Throws std::invalid_argument
/// naming the edge (index, from, to) for an edge to a missing node, a
/// self-edge, non-finite values, or an information matrix that is not
/// symmetric positive definite; and for a node not connected to the fixed
/// node through edges (its pose would be undetermined). Allocates.
PoseGraphResult relax(const PoseGraph& graph, const PoseGraphSettings& settings = {});

/// A guess that needs none: the rotations from the chordal relaxation
/// (Martinec & Pajdla 2007; Carlone et al., "Initialization techniques for
/// 3D SLAM", ICRA 2015): min Σ ω·‖R_to − R_from·R_from_to‖²_F over all 3×3
/// matrices, a linear least-squares problem, each result projected onto
/// SO(3); then the translations that best fit the edges under those
/// rotations (linear again). ω is the smallest eigenvalue of the edge's
/// rotation information, the translations weighed by its translation block.
/// `fixed_node` keeps its pose from the graph. Throws as relax() does.
std::vector<Eigen::Isometry3d> chordal_initialization(const PoseGraph& graph, std::size_t fixed_node = 0);

/// Cost ½ Σ rᵀ·Ω·r of the graph's edges at the given poses (the quantity
/// relax() minimises). Throws as relax() does for bad edges.
double pose_graph_cost(const PoseGraph& graph, const std::vector<Eigen::Isometry3d>& T_world_node);

}  // namespace rise::semantic
