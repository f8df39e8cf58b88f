#include "semantic/pose_graph.hpp"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <Eigen/SparseCholesky>

#include <array>
#include <cmath>
#include <memory>
#include <numeric>
#include <stdexcept>
#include <string>

namespace rise::semantic {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

// One parameter block per node: (tx, ty, tz, qx, qy, qz, qw), the layout of
// ProductManifold<EuclideanManifold<3>, EigenQuaternionManifold>.
using PoseBlock = std::array<double, 7>;

PoseBlock to_block(const Eigen::Isometry3d& T) {
  const Eigen::Quaterniond q(T.linear());
  const Eigen::Vector3d& t = T.translation();
  return {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()};
}

Eigen::Isometry3d from_block(const PoseBlock& b) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(b[6], b[3], b[4], b[5]).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(b[0], b[1], b[2]);
  return T;
}

// r = √Ω · log(T_meas⁻¹ · T_a⁻¹ · T_b): the translation of the error pose
// and its rotation vector, as Ceres' pose_graph_3d example weighs the
// relative-pose error (there with 2·vec(q) for the rotation; here the exact
// angle-axis, which stays right for large loop errors).
struct RelativePoseError {
  RelativePoseError(const Eigen::Isometry3d& T_from_to, const Matrix6d& sqrt_information)
      : q_meas_(T_from_to.linear()), p_meas_(T_from_to.translation()), sqrt_information_(sqrt_information) {}

  template <typename T>
  bool operator()(const T* const a, const T* const b, T* residual_ptr) const {
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_a(a);
    const Eigen::Map<const Eigen::Quaternion<T>> q_a(a + 3);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_b(b);
    const Eigen::Map<const Eigen::Quaternion<T>> q_b(b + 3);

    const Eigen::Quaternion<T> q_a_inv = q_a.conjugate();
    const Eigen::Quaternion<T> q_ab = q_a_inv * q_b;
    const Eigen::Matrix<T, 3, 1> p_ab = q_a_inv * (p_b - p_a);

    const Eigen::Quaternion<T> q_meas_inv = q_meas_.conjugate().template cast<T>();
    const Eigen::Quaternion<T> q_err = q_meas_inv * q_ab;
    const Eigen::Matrix<T, 3, 1> p_err = q_meas_inv * (p_ab - p_meas_.template cast<T>());

    const T q_err_wxyz[4] = {q_err.w(), q_err.x(), q_err.y(), q_err.z()};
    T rotation_vector[3];
    ceres::QuaternionToAngleAxis(q_err_wxyz, rotation_vector);

    Eigen::Matrix<T, 6, 1> error;
    error << p_err, Eigen::Matrix<T, 3, 1>(rotation_vector[0], rotation_vector[1], rotation_vector[2]);
    Eigen::Map<Eigen::Matrix<T, 6, 1>> residual(residual_ptr);
    residual = sqrt_information_.template cast<T>() * error;
    return true;
  }

  Eigen::Quaterniond q_meas_;
  Eigen::Vector3d p_meas_;
  Matrix6d sqrt_information_;
};

std::string edge_name(std::size_t index, const PoseGraphEdge& e) {
  return "pose graph edge " + std::to_string(index) + " (" + std::to_string(e.from) + " -> " +
         std::to_string(e.to) + ")";
}

bool finite(const Eigen::Isometry3d& T) { return T.matrix().allFinite(); }

// √Ω with √Ωᵀ·√Ω = Ω (the upper Cholesky factor), so that ‖√Ω·r‖² = rᵀ·Ω·r.
Matrix6d checked_sqrt_information(std::size_t index, const PoseGraphEdge& e, std::size_t nodes) {
  if (e.from >= nodes || e.to >= nodes) {
    throw std::invalid_argument(edge_name(index, e) + ": no such node (the graph has " + std::to_string(nodes) +
                                " nodes)");
  }
  if (e.from == e.to) throw std::invalid_argument(edge_name(index, e) + ": an edge from a node to itself");
  if (!finite(e.T_from_to)) throw std::invalid_argument(edge_name(index, e) + ": T_from_to is not finite");
  if (!e.information.allFinite() || !e.information.isApprox(e.information.transpose(), 1e-9)) {
    throw std::invalid_argument(edge_name(index, e) + ": information is not a finite symmetric matrix");
  }
  const Eigen::LLT<Matrix6d> llt(e.information);
  if (llt.info() != Eigen::Success) {
    throw std::invalid_argument(edge_name(index, e) + ": information is not positive definite");
  }
  return llt.matrixU();
}

std::vector<Matrix6d> checked_edges(const PoseGraph& graph) {
  const std::size_t nodes = graph.T_world_node.size();
  std::vector<Matrix6d> sqrt_information;
  sqrt_information.reserve(graph.edges.size());
  for (std::size_t i = 0; i < graph.edges.size(); ++i) {
    sqrt_information.push_back(checked_sqrt_information(i, graph.edges[i], nodes));
  }
  return sqrt_information;
}

std::size_t find_root(std::vector<std::size_t>& parent, std::size_t i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

void check_connected(const PoseGraph& graph, std::size_t fixed_node) {
  std::vector<std::size_t> parent(graph.T_world_node.size());
  std::iota(parent.begin(), parent.end(), std::size_t{0});
  for (const auto& e : graph.edges) parent[find_root(parent, e.from)] = find_root(parent, e.to);
  const std::size_t root = find_root(parent, fixed_node);
  for (std::size_t i = 0; i < parent.size(); ++i) {
    if (find_root(parent, i) != root) {
      throw std::invalid_argument("pose graph node " + std::to_string(i) + ": not connected to the fixed node " +
                                  std::to_string(fixed_node) + " by any chain of edges");
    }
  }
}

// One edge of a linear least-squares problem over a 3-vector per node, with
// m right-hand sides at once: the residual P·x_to + Q·x_from − c (3×m),
// weighed by W.
struct LinearEdge {
  std::size_t from, to;
  Eigen::Matrix3d P, Q, W;
  Eigen::MatrixXd c;
};

// The normal equations of Σ ‖P·x_to + Q·x_from − c‖²_W, solved by sparse
// LDLᵀ with node `fixed` held at x_fixed; node k's solution in rows 3k..3k+2.
Eigen::MatrixXd solve_linear(std::size_t nodes, std::size_t fixed, const Eigen::MatrixXd& x_fixed,
                             const std::vector<LinearEdge>& edges) {
  const auto column = [fixed](std::size_t k) { return static_cast<Eigen::Index>(3 * (k < fixed ? k : k - 1)); };
  const auto n = static_cast<Eigen::Index>(3 * (nodes - 1));
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, x_fixed.cols());
  const auto add = [&](std::size_t a, std::size_t b, const Eigen::Matrix3d& block) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) triplets.emplace_back(column(a) + r, column(b) + c, block(r, c));
    }
  };
  for (const auto& e : edges) {
    Eigen::MatrixXd c = e.c;
    if (e.to == fixed) c -= e.P * x_fixed;
    if (e.from == fixed) c -= e.Q * x_fixed;
    if (e.to != fixed) {
      add(e.to, e.to, e.P.transpose() * e.W * e.P);
      rhs.middleRows(column(e.to), 3) += e.P.transpose() * e.W * c;
    }
    if (e.from != fixed) {
      add(e.from, e.from, e.Q.transpose() * e.W * e.Q);
      rhs.middleRows(column(e.from), 3) += e.Q.transpose() * e.W * c;
    }
    if (e.to != fixed && e.from != fixed) {
      add(e.to, e.from, e.P.transpose() * e.W * e.Q);
      add(e.from, e.to, e.Q.transpose() * e.W * e.P);
    }
  }
  Eigen::SparseMatrix<double> H(n, n);
  H.setFromTriplets(triplets.begin(), triplets.end());
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(H);
  if (ldlt.info() != Eigen::Success) throw std::runtime_error("pose graph: chordal initialization: singular system");
  const Eigen::MatrixXd free = ldlt.solve(rhs);
  Eigen::MatrixXd x(3 * static_cast<Eigen::Index>(nodes), x_fixed.cols());
  for (std::size_t k = 0; k < nodes; ++k) {
    x.middleRows(3 * static_cast<Eigen::Index>(k), 3) = k == fixed ? x_fixed : free.middleRows(column(k), 3);
  }
  return x;
}

// The rotation nearest M in the Frobenius norm.
Eigen::Matrix3d nearest_rotation(const Eigen::Matrix3d& M) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixU() * d * svd.matrixV().transpose();
}

}  // namespace

std::vector<Eigen::Isometry3d> chordal_initialization(const PoseGraph& graph, std::size_t fixed_node) {
  const std::size_t nodes = graph.T_world_node.size();
  if (fixed_node >= nodes) {
    throw std::invalid_argument("pose graph: fixed node " + std::to_string(fixed_node) + " is not a node (the graph has " +
                                std::to_string(nodes) + ")");
  }
  checked_edges(graph);
  check_connected(graph, fixed_node);
  std::vector<Eigen::Isometry3d> T = graph.T_world_node;
  if (nodes == 1) return T;

  // R_to − R_from·R_from_to = 0 splits by rows: with x the transpose of one
  // row of R, x_to − R_from_toᵀ·x_from = 0; the three rows are the three
  // right-hand-side columns.
  std::vector<LinearEdge> rotation;
  rotation.reserve(graph.edges.size());
  for (const auto& e : graph.edges) {
    const double w = e.information.bottomRightCorner<3, 3>().selfadjointView<Eigen::Lower>().eigenvalues().minCoeff();
    rotation.push_back({e.from, e.to, Eigen::Matrix3d::Identity(), -e.T_from_to.linear().transpose(),
                        w * Eigen::Matrix3d::Identity(), Eigen::MatrixXd::Zero(3, 3)});
  }
  const Eigen::MatrixXd rows =
      solve_linear(nodes, fixed_node, graph.T_world_node[fixed_node].linear().transpose(), rotation);
  for (std::size_t k = 0; k < nodes; ++k) {
    if (k != fixed_node) {
      T[k].linear() = nearest_rotation(rows.middleRows(3 * static_cast<Eigen::Index>(k), 3).transpose());
    }
  }

  // Our translation error R_meas_ᵀ·(R_fromᵀ·(t_to − t_from) − t_meas) is
  // linear in the translations once the rotations are set.
  std::vector<LinearEdge> translation;
  translation.reserve(graph.edges.size());
  for (const auto& e : graph.edges) {
    const Eigen::Matrix3d M = e.T_from_to.linear().transpose() * T[e.from].linear().transpose();
    translation.push_back({e.from, e.to, M, -M, e.information.topLeftCorner<3, 3>(),
                           e.T_from_to.linear().transpose() * e.T_from_to.translation()});
  }
  const Eigen::MatrixXd t = solve_linear(nodes, fixed_node, graph.T_world_node[fixed_node].translation(), translation);
  for (std::size_t k = 0; k < nodes; ++k) T[k].translation() = t.middleRows(3 * static_cast<Eigen::Index>(k), 3);
  return T;
}

double pose_graph_cost(const PoseGraph& graph, const std::vector<Eigen::Isometry3d>& T_world_node) {
  if (T_world_node.size() != graph.T_world_node.size()) {
    throw std::invalid_argument("pose graph cost: " + std::to_string(T_world_node.size()) + " poses for " +
                                std::to_string(graph.T_world_node.size()) + " nodes");
  }
  const std::vector<Matrix6d> sqrt_information = checked_edges(graph);
  double cost = 0.0;
  for (std::size_t i = 0; i < graph.edges.size(); ++i) {
    const auto& e = graph.edges[i];
    const PoseBlock a = to_block(T_world_node[e.from]), b = to_block(T_world_node[e.to]);
    Vector6d r;
    RelativePoseError(e.T_from_to, sqrt_information[i])(a.data(), b.data(), r.data());
    cost += 0.5 * r.squaredNorm();
  }
  return cost;
}

PoseGraphResult relax(const PoseGraph& graph, const PoseGraphSettings& settings) {
  const std::size_t nodes = graph.T_world_node.size();
  if (nodes == 0) throw std::invalid_argument("pose graph: no nodes");
  if (settings.fixed_node >= nodes) {
    throw std::invalid_argument("pose graph settings: fixed_node " + std::to_string(settings.fixed_node) +
                                " is not a node (the graph has " + std::to_string(nodes) + ")");
  }
  if (settings.max_iterations < 1) throw std::invalid_argument("pose graph settings: max_iterations must be >= 1");
  for (std::size_t i = 0; i < nodes; ++i) {
    if (!finite(graph.T_world_node[i])) {
      throw std::invalid_argument("pose graph node " + std::to_string(i) + ": pose is not finite");
    }
  }
  const std::vector<Matrix6d> sqrt_information = checked_edges(graph);
  check_connected(graph, settings.fixed_node);

  std::vector<PoseBlock> blocks;
  blocks.reserve(nodes);
  for (const auto& T : settings.chordal_initialization ? chordal_initialization(graph, settings.fixed_node)
                                                       : graph.T_world_node) {
    blocks.push_back(to_block(T));
  }

  PoseGraphResult result;
  if (graph.edges.empty()) {  // one node (check_connected refused more): nothing to relax
    result.T_world_node = graph.T_world_node;
    result.converged = true;
    return result;
  }

  ceres::Problem problem;
  for (std::size_t i = 0; i < graph.edges.size(); ++i) {
    const auto& e = graph.edges[i];
    auto* cost = new ceres::AutoDiffCostFunction<RelativePoseError, 6, 7, 7>(
        new RelativePoseError(e.T_from_to, sqrt_information[i]));
    problem.AddResidualBlock(cost, nullptr, blocks[e.from].data(), blocks[e.to].data());
  }
  for (auto& b : blocks) {
    problem.SetManifold(b.data(), new ceres::ProductManifold<ceres::EuclideanManifold<3>, ceres::EigenQuaternionManifold>{});
  }
  problem.SetParameterBlockConstant(blocks[settings.fixed_node].data());

  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  if (!ceres::IsSparseLinearAlgebraLibraryTypeAvailable(options.sparse_linear_algebra_library_type)) {
    options.linear_solver_type = ceres::DENSE_QR;
  }
  options.max_num_iterations = settings.max_iterations;
  options.function_tolerance = settings.function_tolerance;
  options.num_threads = std::max(1, settings.threads);
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;

  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  if (summary.termination_type == ceres::FAILURE) {
    throw std::runtime_error("pose graph: Ceres failed: " + summary.message);
  }

  result.T_world_node.reserve(nodes);
  for (const auto& b : blocks) result.T_world_node.push_back(from_block(b));
  result.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  result.start_cost = summary.initial_cost;
  result.initial_cost =
      settings.chordal_initialization ? pose_graph_cost(graph, graph.T_world_node) : summary.initial_cost;
  result.final_cost = summary.final_cost;
  result.converged = summary.termination_type == ceres::CONVERGENCE;
  return result;
}

}  // namespace rise::semantic
