#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <string>

#include "semantic/pose_graph.hpp"

using namespace rise::semantic;

namespace {
constexpr double kDeg = M_PI / 180.0;

Eigen::Isometry3d pose(double x, double y, double z, double yaw_rad, double pitch_rad = 0.0, double roll_rad = 0.0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

double translation_error_m(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm();
}

double rotation_error_rad(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
}

// A square of 20 poses, 5 per side of 4 m, turning 90° at the corners, with
// a little up-and-down and pitch so that the graph is truly 6D.
std::vector<Eigen::Isometry3d> square_trajectory() {
  std::vector<Eigen::Isometry3d> T;
  for (int side = 0; side < 4; ++side) {
    for (int k = 0; k < 5; ++k) {
      const double s = 0.8 * k;
      const double yaw = side * M_PI / 2;
      Eigen::Vector2d corner[4] = {{0, 0}, {4, 0}, {4, 4}, {0, 4}};
      const Eigen::Vector2d xy = corner[side] + s * Eigen::Vector2d(std::cos(yaw), std::sin(yaw));
      const int i = 5 * side + k;
      T.push_back(pose(xy.x(), xy.y(), 0.05 * std::sin(0.7 * i), yaw, 0.02 * std::cos(0.9 * i), 0.01 * (i % 3)));
    }
  }
  return T;
}

// Perturbs a relative pose by a small random motion: σ_t per axis, σ_r per axis.
Eigen::Isometry3d noisy(const Eigen::Isometry3d& T, std::mt19937& rng, double sigma_t, double sigma_r) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Isometry3d dT = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d r(sigma_r * n(rng), sigma_r * n(rng), sigma_r * n(rng));
  dT.linear() = Eigen::AngleAxisd(r.norm(), r.norm() > 0 ? r.normalized() : Eigen::Vector3d::UnitZ()).toRotationMatrix();
  dT.translation() = Eigen::Vector3d(sigma_t * n(rng), sigma_t * n(rng), sigma_t * n(rng));
  return T * dT;
}

Eigen::Matrix<double, 6, 6> information(double sigma_t, double sigma_r) {
  Eigen::Matrix<double, 6, 1> d;
  d << Eigen::Vector3d::Constant(1.0 / (sigma_t * sigma_t)), Eigen::Vector3d::Constant(1.0 / (sigma_r * sigma_r));
  return d.asDiagonal();
}

// Chains the odometry edges from the first true pose: the dead-reckoned guess.
std::vector<Eigen::Isometry3d> chain(const Eigen::Isometry3d& T0, const std::vector<PoseGraphEdge>& odometry) {
  std::vector<Eigen::Isometry3d> T{T0};
  for (const auto& e : odometry) T.push_back(T.back() * e.T_from_to);
  return T;
}
}  // namespace

TEST_CASE("relaxing a drifting square with one loop edge takes the poses far below the odometry drift", "[semantic]") {
  const auto truth = square_trajectory();
  std::mt19937 rng(42);
  // Odometry as wheels give it: a systematic yaw drift of 1.5° per step
  // (what the loop can undo) plus a little random noise (what it cannot).
  const double sigma_t = 0.003, sigma_r = 0.1 * kDeg, yaw_bias = 1.5 * kDeg;
  const Eigen::Isometry3d bias = pose(0, 0, 0, yaw_bias);
  PoseGraph graph;
  for (std::size_t i = 0; i + 1 < truth.size(); ++i) {
    graph.edges.push_back({i, i + 1, noisy(truth[i].inverse() * truth[i + 1] * bias, rng, sigma_t, sigma_r),
                           information(sigma_t, yaw_bias)});
  }
  graph.T_world_node = chain(truth[0], graph.edges);
  // The loop: the last pose seen from the first, measured 10× more precisely.
  const std::size_t last = truth.size() - 1;
  graph.edges.push_back({0, last, noisy(truth[0].inverse() * truth[last], rng, 0.002, 0.1 * kDeg),
                         information(0.002, 0.1 * kDeg)});

  double drift_t = 0, drift_r = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    drift_t = std::max(drift_t, translation_error_m(graph.T_world_node[i], truth[i]));
    drift_r = std::max(drift_r, rotation_error_rad(graph.T_world_node[i], truth[i]));
  }
  INFO("odometry drift " << drift_t << " m, " << drift_r / kDeg << " deg");
  REQUIRE(drift_t > 1.0);  // the guess is really off: the test means something

  const PoseGraphResult r = relax(graph);
  CHECK(r.converged);
  CHECK(r.iterations > 0);
  CHECK(r.final_cost < 0.05 * r.initial_cost);
  CHECK(r.initial_cost == Approx(pose_graph_cost(graph, graph.T_world_node)).epsilon(1e-9));
  CHECK(r.final_cost == Approx(pose_graph_cost(graph, r.T_world_node)).epsilon(1e-6));
  REQUIRE(r.T_world_node.size() == truth.size());
  CHECK(translation_error_m(r.T_world_node[0], truth[0]) < 1e-12);  // the fixed node
  double max_t = 0, max_r = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    max_t = std::max(max_t, translation_error_m(r.T_world_node[i], truth[i]));
    max_r = std::max(max_r, rotation_error_rad(r.T_world_node[i], truth[i]));
  }
  INFO("relaxed " << max_t << " m, " << max_r / kDeg << " deg");
  CHECK(max_t < 0.05 * drift_t);
  CHECK(max_r < 0.05 * drift_r);
  // The loop is closed: the last pose agrees with its precise loop edge.
  CHECK(translation_error_m(r.T_world_node[last], truth[last]) < 0.05);
}

TEST_CASE("a pose graph without loops stays as its chained odometry gives it", "[semantic]") {
  const auto truth = square_trajectory();
  std::mt19937 rng(7);
  PoseGraph graph;
  for (std::size_t i = 0; i + 1 < truth.size(); ++i) {
    graph.edges.push_back({i, i + 1, noisy(truth[i].inverse() * truth[i + 1], rng, 0.02, 1.0 * kDeg),
                           information(0.02, 1.0 * kDeg)});
  }
  graph.T_world_node = chain(truth[0], graph.edges);
  // Start from a disturbed guess: the relaxation must bring it back to the chain.
  PoseGraph disturbed = graph;
  for (std::size_t i = 1; i < disturbed.T_world_node.size(); ++i) {
    disturbed.T_world_node[i] = noisy(disturbed.T_world_node[i], rng, 0.05, 2.0 * kDeg);
  }
  for (const PoseGraph* g : {&graph, &disturbed}) {
    const PoseGraphResult r = relax(*g);
    CHECK(r.converged);
    CHECK(r.final_cost < 1e-10);
    for (std::size_t i = 0; i < truth.size(); ++i) {
      CHECK(translation_error_m(r.T_world_node[i], graph.T_world_node[i]) < 1e-5);
      CHECK(rotation_error_rad(r.T_world_node[i], graph.T_world_node[i]) < 1e-6);
    }
  }
}

TEST_CASE("a pose graph with a bad edge or node is refused naming it", "[semantic]") {
  PoseGraph graph;
  graph.T_world_node = {pose(0, 0, 0, 0), pose(1, 0, 0, 0), pose(2, 0, 0, 0)};
  graph.edges = {{0, 1, pose(1, 0, 0, 0), information(0.01, 0.01)}, {1, 2, pose(1, 0, 0, 0), information(0.01, 0.01)}};
  REQUIRE_NOTHROW(relax(graph));

  const auto error_of = [](const PoseGraph& g, const PoseGraphSettings& s = {}) {
    try {
      relax(g, s);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  SECTION("an edge to a missing node") {
    graph.edges[1].to = 5;
    CHECK(error_of(graph) == "pose graph edge 1 (1 -> 5): no such node (the graph has 3 nodes)");
  }
  SECTION("an edge from a node to itself") {
    graph.edges[0].to = 0;
    CHECK(error_of(graph) == "pose graph edge 0 (0 -> 0): an edge from a node to itself");
  }
  SECTION("an information matrix that is not positive definite") {
    graph.edges[1].information(5, 5) = -1.0;
    CHECK(error_of(graph) == "pose graph edge 1 (1 -> 2): information is not positive definite");
  }
  SECTION("an asymmetric information matrix") {
    graph.edges[0].information(0, 3) = 0.5;
    CHECK(error_of(graph) == "pose graph edge 0 (0 -> 1): information is not a finite symmetric matrix");
  }
  SECTION("a measurement that is not finite") {
    graph.edges[0].T_from_to.translation().x() = std::nan("");
    CHECK(error_of(graph) == "pose graph edge 0 (0 -> 1): T_from_to is not finite");
  }
  SECTION("a node no edge reaches") {
    graph.T_world_node.push_back(pose(3, 0, 0, 0));
    CHECK(error_of(graph) == "pose graph node 3: not connected to the fixed node 0 by any chain of edges");
  }
  SECTION("a fixed node that does not exist") {
    PoseGraphSettings s;
    s.fixed_node = 3;
    CHECK(error_of(graph, s) == "pose graph settings: fixed_node 3 is not a node (the graph has 3)");
  }
}
