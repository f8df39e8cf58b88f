#include "semantic/pose_graph_io.hpp"

#include <catch2/catch.hpp>

#include "tests/test_data.hpp"

#include <unistd.h>

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace sem = rise::semantic;
namespace fs = std::filesystem;

namespace {

using rise::test::data_file;
using Matrix6d = Eigen::Matrix<double, 6, 6>;
constexpr double kDeg = M_PI / 180.0;

std::string write(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / ("rise_pose_graph_io_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path p = dir / name;
  std::ofstream(p) << text;
  return p.string();
}

std::string error_of(const std::string& path) {
  try {
    (void)sem::read_pose_graph(path);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

std::string numbers(const double* v, int n) {
  std::string s;
  char b[32];
  for (int i = 0; i < n; ++i) {
    std::snprintf(b, sizeof b, " %.17g", v[i]);
    s += b;
  }
  return s;
}

std::string quaternion_pose(const Eigen::Isometry3d& T) {
  const Eigen::Quaterniond q(T.linear());
  const double v[7] = {T.translation().x(), T.translation().y(), T.translation().z(), q.x(), q.y(), q.z(), q.w()};
  return numbers(v, 7);
}

std::string upper_triangle(const Matrix6d& m) {
  std::string s;
  for (int i = 0; i < 6; ++i) {
    for (int j = i; j < 6; ++j) s += numbers(&m(i, j), 1);
  }
  return s;
}

Eigen::Isometry3d pose(const Eigen::Vector3d& t, const Eigen::Vector3d& rotation_vector) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(rotation_vector.norm(), rotation_vector.normalized()).toRotationMatrix();
  T.translation() = t;
  return T;
}

// RMS position and rotation error (m, deg) of `estimate` against `truth`
// after the rigid transform that maps estimate[0] onto truth[0].
std::pair<double, double> anchored_ate(const std::vector<Eigen::Isometry3d>& estimate,
                                       const std::vector<Eigen::Isometry3d>& truth) {
  const Eigen::Isometry3d align = truth[0] * estimate[0].inverse();
  double t2 = 0.0, r2 = 0.0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const Eigen::Isometry3d E = truth[i].inverse() * align * estimate[i];
    t2 += E.translation().squaredNorm();
    r2 += std::pow(Eigen::AngleAxisd(E.linear()).angle(), 2);
  }
  const double n = static_cast<double>(truth.size());
  return {std::sqrt(t2 / n), std::sqrt(r2 / n) / kDeg};
}

}  // namespace

TEST_CASE("pose graph reader reads every shared graph with the MANIFEST's counts", "[semantic]") {
  // Loop closures: edges i -> j with j != i + 1 (MANIFEST.md section 6; the
  // garage's, which it does not give, counted with awk).
  const auto [file, nodes, edges, loops, planar, chained] =
      GENERATE(table<std::string, std::size_t, std::size_t, std::size_t, bool, bool>({
          {"david-m-rosen_SE-Sync/intel.g2o", 1728, 2512, 785, true, false},
          {"david-m-rosen_SE-Sync/MIT.g2o", 808, 827, 20, true, false},
          {"david-m-rosen_SE-Sync/CSAIL.g2o", 1045, 1172, 128, true, true},
          {"david-m-rosen_SE-Sync/manhattan.g2o", 3500, 5453, 1954, true, true},
          {"david-m-rosen_SE-Sync/sphere2500.g2o", 2500, 4949, 2450, false, false},
          {"david-m-rosen_SE-Sync/parking-garage.g2o", 1661, 6275, 4615, false, false},
          {"borglab_gtsam/sphere2500_groundtruth.txt", 2500, 4949, 2450, false, true},
      }));
  const std::string path = data_file("posegraphs/" + file);
  if (path.empty()) {
    WARN("skipped: RISE_TEST_DATA/posegraphs/" << file << " not found");
    return;
  }
  CAPTURE(file);
  const sem::PoseGraphFile f = sem::read_pose_graph(path);
  CHECK(f.graph.T_world_node.size() == nodes);
  CHECK(f.ids.size() == nodes);
  CHECK(f.graph.edges.size() == edges);
  CHECK(f.loop_closures == loops);
  CHECK(f.planar == planar);
  CHECK(f.chained == chained);
  CHECK(f.ignored.empty());
  if (planar) {
    for (const auto& T : f.graph.T_world_node) {
      REQUIRE(T.translation().z() == 0.0);
      REQUIRE(T.linear()(2, 2) == Approx(1.0).margin(1e-12));
    }
  }
}

TEST_CASE("sphere2500's ground truth chained from EDGE3 agrees with every loop closure", "[semantic]") {
  // MANIFEST.md: R = Rz(yaw)·Ry(pitch)·Rx(roll); with that convention the
  // 2450 loop-closure edges agree with the chained poses to 2.3e-4.
  const std::string path = data_file("posegraphs/borglab_gtsam/sphere2500_groundtruth.txt");
  if (path.empty()) {
    WARN("skipped: RISE_TEST_DATA/posegraphs/borglab_gtsam/sphere2500_groundtruth.txt not found");
    return;
  }
  const sem::PoseGraphFile f = sem::read_pose_graph(path);
  double worst_m = 0.0, worst_rad = 0.0;
  for (const auto& e : f.graph.edges) {
    const Eigen::Isometry3d E =
        e.T_from_to.inverse() * f.graph.T_world_node[e.from].inverse() * f.graph.T_world_node[e.to];
    worst_m = std::max(worst_m, E.translation().norm());
    worst_rad = std::max(worst_rad, Eigen::AngleAxisd(E.linear()).angle());
  }
  CHECK(worst_m < 1e-3);
  CHECK(worst_rad < 1e-3);
}

TEST_CASE("pose graph reader converts g2o's quaternion information to the rotation vector's", "[semantic]") {
  // An edge with a known covariance: σ 0.1 m on x, σ 2° about x. g2o weighs
  // q.xyz = ½·(rotation vector), so its file holds 4/σ² for the rotation.
  const double sigma_m = 0.1, sigma_rad = 2.0 * kDeg;
  Matrix6d omega_g2o = Matrix6d::Identity();
  omega_g2o(0, 0) = 1.0 / (sigma_m * sigma_m);
  omega_g2o(3, 3) = 4.0 / (sigma_rad * sigma_rad);
  // ... and a full SPD block elsewhere, to check the cross terms.
  Matrix6d A;
  A << 3, 1, 0, 2, 0, 1,  //
      0, 4, 1, 0, 1, 0,   //
      1, 0, 5, 1, 0, 2,   //
      0, 2, 0, 6, 1, 0,   //
      1, 0, 1, 0, 7, 1,   //
      0, 1, 0, 2, 0, 8;
  omega_g2o += A.transpose() * A;

  const Eigen::Isometry3d X0 = pose({1, 2, 3}, {0.1, -0.2, 0.3});
  const Eigen::Isometry3d Z = pose({0.5, -0.2, 0.1}, {0.05, 0.02, -0.3});
  const Eigen::Isometry3d X1 = X0 * Z * pose({0.01, -0.02, 0.015}, {2e-3, -1e-3, 1.5e-3});
  const std::string path = write("information.g2o", "VERTEX_SE3:QUAT 0" + quaternion_pose(X0) +
                                                        "\nVERTEX_SE3:QUAT 1" + quaternion_pose(X1) +
                                                        "\nEDGE_SE3:QUAT 0 1" + quaternion_pose(Z) +
                                                        upper_triangle(omega_g2o) + "\nFIX 0\n");
  const sem::PoseGraphFile f = sem::read_pose_graph(path);
  REQUIRE(f.graph.edges.size() == 1);
  REQUIRE(f.fixed == std::vector<std::size_t>{0});
  const Matrix6d& omega = f.graph.edges[0].information;

  SECTION("the known σ comes back as 1/σ² for translation and rotation alike") {
    Matrix6d diagonal_g2o = Matrix6d::Identity();
    diagonal_g2o(0, 0) = 1.0 / (sigma_m * sigma_m);
    diagonal_g2o(3, 3) = 4.0 / (sigma_rad * sigma_rad);
    const std::string p = write("sigma.g2o", "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\nVERTEX_SE3:QUAT 1 1 0 0 0 0 0 1\n"
                                             "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1" +
                                                 upper_triangle(diagonal_g2o) + "\n");
    const Matrix6d o = sem::read_pose_graph(p).graph.edges[0].information;
    CHECK(o(0, 0) == Approx(1.0 / (sigma_m * sigma_m)).epsilon(1e-12));
    CHECK(o(3, 3) == Approx(1.0 / (sigma_rad * sigma_rad)).epsilon(1e-12));
    CHECK(o(4, 4) == Approx(0.25).epsilon(1e-12));
  }
  SECTION("the blocks scale by 1, ½ and ¼") {
    CHECK(omega.topLeftCorner<3, 3>().isApprox(omega_g2o.topLeftCorner<3, 3>(), 1e-12));
    CHECK(omega.topRightCorner<3, 3>().isApprox(0.5 * omega_g2o.topRightCorner<3, 3>(), 1e-12));
    CHECK(omega.bottomLeftCorner<3, 3>().isApprox(0.5 * omega_g2o.bottomLeftCorner<3, 3>(), 1e-12));
    CHECK(omega.bottomRightCorner<3, 3>().isApprox(0.25 * omega_g2o.bottomRightCorner<3, 3>(), 1e-12));
  }
  SECTION("our cost of a small error is g2o's χ²/2") {
    // g2o's EdgeSE3::computeError: toVectorMQT(Z⁻¹·X0⁻¹·X1), (t, q.xyz) with w ≥ 0.
    const Eigen::Isometry3d delta = Z.inverse() * X0.inverse() * X1;
    Eigen::Quaterniond q(delta.linear());
    if (q.w() < 0) q.coeffs() *= -1.0;
    Eigen::Matrix<double, 6, 1> e;
    e << delta.translation(), q.vec();
    const double chi2 = e.dot(omega_g2o * e);
    CHECK(2.0 * sem::pose_graph_cost(f.graph, f.graph.T_world_node) == Approx(chi2).epsilon(1e-4));
  }
}

TEST_CASE("pose graph reader lifts SE(2) into the plane and keeps it there", "[semantic]") {
  // A triangle with a loop that disagrees by 0.1 m and 3°: relaxing spreads
  // the error in the plane, never out of it.
  const std::string path = write("planar.g2o",
                                 "# a comment\n"
                                 "VERTEX_SE2 5 0 0 0\n"
                                 "VERTEX_SE2 6 2 0 2.0943951\n"
                                 "VERTEX_SE2 9 1 1.7320508 -2.0943951\n"
                                 "PARAMS_SE2OFFSET 0 0 0 0\n"
                                 "EDGE_SE2 5 6 2 0 2.0943951 100 5 2 200 3 1000\n"
                                 "EDGE_SE2 6 9 2 0 2.0943951 100 0 0 100 0 1000\n"
                                 "EDGE_SE2 9 5 2.1 0 2.1467549 100 0 0 100 0 1000\n");
  const sem::PoseGraphFile f = sem::read_pose_graph(path);
  CHECK(f.ids == std::vector<long long>{5, 6, 9});
  CHECK(f.planar);
  CHECK(f.loop_closures == 2);  // 6 -> 9 and 9 -> 5: ids that do not follow
  REQUIRE(f.ignored.size() == 1);
  CHECK(f.ignored[0] == std::pair<std::string, std::size_t>{"PARAMS_SE2OFFSET", 1});

  const auto& e = f.graph.edges[0];
  CHECK(e.from == 0);
  CHECK(e.to == 1);
  CHECK(e.T_from_to.translation().isApprox(Eigen::Vector3d(2, 0, 0)));
  CHECK(Eigen::AngleAxisd(e.T_from_to.linear()).angle() == Approx(2.0943951).epsilon(1e-9));
  CHECK(Eigen::AngleAxisd(e.T_from_to.linear()).axis().isApprox(Eigen::Vector3d::UnitZ()));
  Matrix6d expected = Matrix6d::Zero();
  expected(0, 0) = 100;
  expected(0, 1) = expected(1, 0) = 5;
  expected(0, 5) = expected(5, 0) = 2;
  expected(1, 1) = 200;
  expected(1, 5) = expected(5, 1) = 3;
  expected(5, 5) = 1000;
  expected(2, 2) = expected(3, 3) = expected(4, 4) = sem::kPlanarStiffness * 1000;
  CHECK(e.information == expected);

  const sem::PoseGraphResult r = sem::relax(f.graph);
  CHECK(r.final_cost < 0.5 * r.initial_cost);
  for (const auto& T : r.T_world_node) {
    CHECK(std::abs(T.translation().z()) < 1e-9);
    CHECK(T.linear()(2, 2) == Approx(1.0).margin(1e-12));
  }
}

TEST_CASE("pose graph reader reads TORO's EDGE3 angles as Rz(yaw)·Ry(pitch)·Rx(roll)", "[semantic]") {
  const std::string path = write("toro.graph",
                                 "EDGE3 0 1 1 2 3 0.1 0.2 0.3 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n");
  const sem::PoseGraphFile f = sem::read_pose_graph(path);
  REQUIRE(f.chained);
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  CHECK(f.graph.T_world_node[1].linear().isApprox(R, 1e-12));
  CHECK(f.graph.T_world_node[1].translation().isApprox(Eigen::Vector3d(1, 2, 3)));
  CHECK(f.graph.T_world_node[0].isApprox(Eigen::Isometry3d::Identity()));
}

TEST_CASE("pose graph reader names the file, line and tag of bad input", "[semantic]") {
  const std::string edge01 = "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n";
  const std::string two = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\n";
  const auto [text, expected] = GENERATE_REF(table<std::string, std::string>({
      {"EDGE_SE2 0 1 1 0 0 1 0 0 1 0\n", "bad.g2o:1: EDGE_SE2: 10 values, expected 11"},
      {"VERTEX_SE2 0 0 0 0\n" + edge01, "bad.g2o:2: EDGE_SE2: unknown vertex 1"},
      {"VERTEX_SE2 0 0 nan 0\n", "bad.g2o:1: VERTEX_SE2: value 3 is not finite"},
      {"VERTEX_SE2 0 0 zero 0\n", "bad.g2o:1: VERTEX_SE2: not a number: 'zero'"},
      {"VERTEX_SE2 x 0 0 0\n", "bad.g2o:1: VERTEX_SE2: vertex id: not a number: 'x'"},
      {"VERTEX_SE3:QUAT 0 0 0 0 0 0 0 2\n", "bad.g2o:1: VERTEX_SE3:QUAT: quaternion norm 2.000000 is not 1"},
      {two + "VERTEX_SE2 0 0 0 0\n", "bad.g2o:3: VERTEX_SE2: vertex 0 given twice (first on line 1)"},
      {two + "EDGE_SE2 0 1 1 0 0 1 0 0 -1 0 1\n", "bad.g2o:3: EDGE_SE2: information matrix is not positive definite"},
      {two + "EDGE_SE2 1 1 1 0 0 1 0 0 1 0 1\n", "bad.g2o:3: EDGE_SE2: an edge from vertex 1 to itself"},
      {two + edge01 + "FIX 7\n", "bad.g2o:4: FIX: unknown vertex 7"},
      {edge01 + "EDGE_SE2 2 3 1 0 0 1 0 0 1 0 1\n",
       "bad.g2o: vertex 2: the file has no VERTEX lines and no chain of i -> i+1 edges from vertex 0 reaches it"},
      {two, "bad.g2o: no edges"},
  }));
  CAPTURE(text);
  CHECK_THAT(error_of(write("bad.g2o", text)), Catch::Contains(expected));
  CHECK_THAT(error_of("/nonexistent/graph.g2o"), Catch::Contains("/nonexistent/graph.g2o: cannot open"));
}

TEST_CASE("relax() brings sphere2500 to within its measured error of the ground truth", "[semantic]") {
  const std::string noisy = data_file("posegraphs/david-m-rosen_SE-Sync/sphere2500.g2o");
  const std::string truth = data_file("posegraphs/borglab_gtsam/sphere2500_groundtruth.txt");
  if (noisy.empty() || truth.empty()) {
    WARN("skipped: RISE_TEST_DATA/posegraphs: sphere2500.g2o or sphere2500_groundtruth.txt not found");
    return;
  }
  const sem::PoseGraphFile f = sem::read_pose_graph(noisy), gt = sem::read_pose_graph(truth);
  REQUIRE(f.ids == gt.ids);
  sem::PoseGraphSettings settings;
  settings.threads = 2;
  const sem::PoseGraphResult r = sem::relax(f.graph, settings);
  // Measured (semantic/README.md): the g2o vertices 41.2 m / 65.2° RMS from
  // the truth, relaxed 2.11 m / 2.74° (anchored at pose 0); cost 1.27e6 -> 363.6.
  const auto [before_m, before_deg] = anchored_ate(f.graph.T_world_node, gt.graph.T_world_node);
  const auto [after_m, after_deg] = anchored_ate(r.T_world_node, gt.graph.T_world_node);
  CHECK(before_m > 40.0);
  CHECK(after_m < 2.5);
  CHECK(after_deg < 3.2);
  CHECK(r.converged);
  CHECK(r.final_cost < 1e-3 * r.initial_cost);
  CHECK(r.final_cost < 364.0);
  (void)before_deg;
}

TEST_CASE("relax() from its default chordal guess finds MIT's minimum that odometry misses", "[semantic]") {
  const std::string path = data_file("posegraphs/david-m-rosen_SE-Sync/MIT.g2o");
  if (path.empty()) {
    WARN("skipped: RISE_TEST_DATA/posegraphs/david-m-rosen_SE-Sync/MIT.g2o not found");
    return;
  }
  const sem::PoseGraphFile f = sem::read_pose_graph(path);
  // Measured: from the chordal guess cost 20.58 in 17 iterations; from the
  // file's odometry 15234 after 100 (385 after 389).
  const sem::PoseGraphResult r = sem::relax(f.graph);
  CHECK(r.converged);
  CHECK(r.final_cost < 21.0);
  sem::PoseGraphSettings odometry;
  odometry.chordal_initialization = false;
  CHECK(sem::relax(f.graph, odometry).final_cost > 100.0);
}
