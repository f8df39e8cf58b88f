#pragma once

// Pose graphs from files: g2o's text format (the SE(3) and SE(2) types of
// RainerKuemmerle/g2o, types/slam3d and types/slam2d) and TORO's 3D EDGE3
// lines, as the public benchmark graphs come (intel, MIT, CSAIL, manhattan,
// sphere2500, parking-garage), read into our PoseGraph for relax().

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "semantic/pose_graph.hpp"

namespace rise::semantic {

struct PoseGraphFile {
  PoseGraph graph;                   ///< node i is the file's vertex ids[i]
  std::vector<long long> ids;        ///< in order of first appearance
  std::vector<std::size_t> fixed;    ///< nodes named by FIX lines
  std::size_t loop_closures = 0;     ///< edges i -> j with j != i + 1 (ids)
  bool planar = false;               ///< read from VERTEX_SE2 / EDGE_SE2
  bool chained = false;              ///< no VERTEX lines: the guess chains the i -> i+1 edges
  std::vector<std::pair<std::string, std::size_t>> ignored;  ///< other tags and their line counts
};

/// Reads a g2o file (VERTEX_SE3:QUAT, EDGE_SE3:QUAT, VERTEX_SE2, EDGE_SE2,
/// FIX) or a TORO 3D file (VERTEX3, EDGE3); other tags are counted in
/// `ignored`. Converts each edge's information to PoseGraphEdge's
/// (translation, rotation vector) error:
/// - EDGE_SE3:QUAT: g2o weighs (t, q.xyz of the error quaternion, w ≥ 0), and
///   q.xyz = ½·(rotation vector) to first order, so the rotation block is
///   scaled by ¼ and the translation–rotation blocks by ½;
/// - EDGE_SE2 (x y θ, information I11 I12 I13 I22 I23 I33) is lifted into
///   the plane z = 0: θ is the rotation vector's z; z, roll and pitch get a
///   stiff information (kPlanarStiffness times the edge's largest diagonal)
///   so the relaxed graph stays planar;
/// - EDGE3 (x y z roll pitch yaw, R = Rz(yaw)·Ry(pitch)·Rx(roll)): its
///   (roll, pitch, yaw) information is taken as the rotation vector's (equal
///   to first order at the identity).
/// Without VERTEX lines the initial guess chains the i -> i+1 edges from the
/// smallest id at the identity. Throws std::runtime_error "path:line: TAG:
/// message" for a wrong number count, a non-finite value, a quaternion whose
/// norm is not 1 (±1e-3), a duplicate vertex id, an edge to an unknown vertex
/// (when the file has VERTEX lines), an information matrix that is not
/// positive definite, a FIX of an unknown vertex; "path: vertex N: ..." for a
/// node no chain reaches; "path: no edges" for a file without edges.
PoseGraphFile read_pose_graph(const std::string& path);

/// Information given to z, roll and pitch of a lifted SE(2) edge, relative
/// to the edge's largest diagonal value.
inline constexpr double kPlanarStiffness = 1e3;

}  // namespace rise::semantic
