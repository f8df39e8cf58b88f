#include "semantic/icp.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include "semantic/voxel_grid.hpp"
#include "tests/semantic/synthetic_room.hpp"

namespace sem = rise::semantic;
using sem::test::rotation_error_deg;
using sem::test::translation_error_m;

namespace {

// Two samplings of the synthetic room, the second seen 6° and 0.18 m away.
struct MovedRoom {
  sem::Cloud target = sem::test::synthetic_room(20000, 3);
  Eigen::Isometry3d T_true = sem::test::pose(-6.0, 0.0, 1.0, {-0.15, 0.1, 0.0});
  sem::Cloud source = sem::transformed(sem::test::synthetic_room(20000, 4), T_true.inverse());
};

}  // namespace

TEST_CASE("icp recovers a known 10 degree, 0.2 m motion of a synthetic room", "[semantic]") {
  const sem::Cloud target = sem::test::synthetic_room(40000, 1);
  const Eigen::Isometry3d T_true = sem::test::pose(10.0, 2.0, -1.5, {0.2, -0.1, 0.05});
  // The source is another sampling of the room, seen from the moved sensor.
  const sem::Cloud source = sem::transformed(sem::test::synthetic_room(40000, 2), T_true.inverse());

  sem::IcpSettings s;
  // 40000 points on ~120 m² are ~5.5 cm apart: pairing down to 0.1 m keeps
  // every point paired once aligned.
  s.max_iterations = 50;
  s.max_correspondence_m = 0.5;
  s.min_correspondence_m = 0.1;
  const auto threads = GENERATE(1, 2);
  s.threads = threads;
  const bool exact = GENERATE(false, true);
  s.exact_neighbours = exact;

  SECTION("point to point") {
    s.metric = sem::IcpMetric::PointToPoint;
    const auto r = sem::icp(source, target, Eigen::Isometry3d::Identity(), s);
    CHECK(rotation_error_deg(r.T_target_source, T_true) < 0.02);
    CHECK(translation_error_m(r.T_target_source, T_true) < 0.001);
    // Sampled far cells leave a few pairs beyond the finest level unfound.
    CHECK(r.inlier_ratio > (exact ? 0.99 : 0.95));
    CHECK(r.rmse_m < 0.04);  // two samplings ~5.5 cm apart: ~3 cm to the nearest point
  }
  SECTION("point to plane, with a Huber kernel") {
    sem::Cloud t = target;
    sem::estimate_normals(t, 10, Eigen::Vector3f(3, 2, 1.5));
    s.metric = sem::IcpMetric::PointToPlane;
    s.huber_m = 0.02;
    const auto r = sem::icp(source, t, Eigen::Isometry3d::Identity(), s);
    CHECK(rotation_error_deg(r.T_target_source, T_true) < 0.02);
    CHECK(translation_error_m(r.T_target_source, T_true) < 0.001);
    CHECK(r.converged);
    CHECK(r.iterations < 50);
    CHECK(r.inlier_ratio > 0.99);
  }
}

TEST_CASE("icp gives the same answer on one thread and on two", "[semantic]") {
  const MovedRoom room;
  const sem::Cloud &target = room.target, &source = room.source;
  sem::IcpSettings s;
  s.threads = 1;
  const auto one = sem::icp(source, target, Eigen::Isometry3d::Identity(), s);
  s.threads = 2;
  const auto two = sem::icp(source, target, Eigen::Isometry3d::Identity(), s);
  // Fixed chunks summed in order: bit for bit the same, whatever the schedule.
  CHECK(one.iterations == two.iterations);
  CHECK(one.T_target_source.matrix() == two.T_target_source.matrix());
  CHECK(one.rmse_m == two.rmse_m);
}

TEST_CASE("icp onto a prepared target gives icp's answer, from any number of starts", "[semantic]") {
  MovedRoom room;
  sem::estimate_normals(room.target, 10, Eigen::Vector3f(3, 2, 1.5));
  const sem::Cloud &target = room.target, &source = room.source;
  const Eigen::Isometry3d& T_true = room.T_true;
  sem::IcpSettings s;
  s.metric = GENERATE(sem::IcpMetric::PointToPoint, sem::IcpMetric::PointToPlane);
  const sem::IcpTarget prepared(target, s);
  for (const Eigen::Isometry3d& start : {Eigen::Isometry3d::Identity(), sem::test::pose(3.0, 0.0, 0.0, {0.1, 0, 0})}) {
    const auto plain = sem::icp(source, target, start, s);
    const auto again = sem::icp(source, prepared, start);
    CHECK(plain.iterations == again.iterations);
    CHECK(plain.T_target_source.matrix() == again.T_target_source.matrix());
    CHECK(plain.rmse_m == again.rmse_m);
  }
  CHECK(rotation_error_deg(sem::icp(source, prepared, Eigen::Isometry3d::Identity()).T_target_source, T_true) < 0.1);
  CHECK_THROWS_AS(sem::IcpTarget(sem::Cloud{}, s), std::invalid_argument);
  CHECK_THROWS_AS(sem::icp(sem::Cloud{}, prepared, Eigen::Isometry3d::Identity()), std::invalid_argument);
}

TEST_CASE("icp stops where its caller's condition holds, with the iterations and pairs up to there", "[semantic]") {
  const MovedRoom room;
  const sem::Cloud &target = room.target, &source = room.source;
  sem::IcpSettings s;
  s.max_iterations = 50;
  s.min_correspondence_m = 0.1;  // the points are ~8 cm apart: all pair once aligned
  s.translation_epsilon_m = 1e-4;
  s.rotation_epsilon_rad = 1e-4;
  const sem::IcpTarget prepared(target, s);
  const auto full = sem::icp(source, prepared, Eigen::Isometry3d::Identity());
  INFO(full.iterations << " iterations, last step " << full.last_step_m);
  REQUIRE(full.converged);
  REQUIRE(full.iterations > 4);
  CHECK_FALSE(full.stopped);
  // Stopped after the third update: the same first three steps, not converged.
  int seen = 0;
  const auto third = sem::icp(source, prepared, Eigen::Isometry3d::Identity(),
                              [&](const Eigen::Isometry3d&, const sem::IcpResult& so_far) {
                                CHECK(so_far.iterations == ++seen);
                                return so_far.iterations == 3;
                              });
  CHECK(third.stopped);
  CHECK_FALSE(third.converged);
  CHECK(third.iterations == 3);
  // Its answer is the pose the condition saw.
  Eigen::Isometry3d at_stop = Eigen::Isometry3d::Identity();
  sem::icp(source, prepared, Eigen::Isometry3d::Identity(), [&](const Eigen::Isometry3d& T, const sem::IcpResult& r) {
    if (r.iterations == 3) at_stop = T;
    return r.iterations == 3;
  });
  CHECK(third.T_target_source.isApprox(at_stop, 1e-9));
  // Stopped once within 1 cm of the converged answer: fewer iterations, close to it.
  const auto near = sem::icp(source, prepared, Eigen::Isometry3d::Identity(),
                             [&](const Eigen::Isometry3d& T, const sem::IcpResult&) {
                               return (T.translation() - full.T_target_source.translation()).norm() < 0.01;
                             });
  CHECK(near.stopped);
  CHECK(near.iterations < full.iterations);
  CHECK(translation_error_m(near.T_target_source, full.T_target_source) < 0.01);
}

TEST_CASE("icp reusing pairs gives the pairs and transform a search would, to the bit", "[semantic]") {
  sem::Cloud target = sem::test::synthetic_room(20000, 3);
  sem::estimate_normals(target, 10, Eigen::Vector3f(3, 2, 1.5));
  const Eigen::Isometry3d T_true = sem::test::pose(-6.0, 1.0, 1.0, {-0.15, 0.1, 0.05});
  const sem::Cloud source = sem::transformed(sem::test::synthetic_room(20000, 4), T_true.inverse());
  sem::IcpSettings s;
  s.metric = GENERATE(sem::IcpMetric::PointToPoint, sem::IcpMetric::PointToPlane);
  s.exact_neighbours = GENERATE(false, true);
  // A shrinking pairing distance, and a fixed one (the benchmark's).
  s.max_correspondence_m = GENERATE(0.5, 0.1);
  s.min_correspondence_m = 0.1;
  s.translation_epsilon_m = s.rotation_epsilon_rad = 0.0;
  s.reuse_pairs = false;
  const auto searched = sem::icp(source, target, Eigen::Isometry3d::Identity(), s);
  s.reuse_pairs = true;
  const auto reused = sem::icp(source, target, Eigen::Isometry3d::Identity(), s);
  CHECK(searched.iterations == reused.iterations);
  CHECK(searched.T_target_source.matrix() == reused.T_target_source.matrix());
  CHECK(searched.rmse_m == reused.rmse_m);
  CHECK(searched.inlier_ratio == reused.inlier_ratio);
  // The fixed 10 cm pairing cannot pull in a 6 degree turn; the shrinking one does.
  if (s.max_correspondence_m > 0.2) CHECK(rotation_error_deg(reused.T_target_source, T_true) < 0.05);
}

TEST_CASE("icp refuses empty clouds, missing normals and bad settings", "[semantic]") {
  const sem::Cloud room = sem::test::synthetic_room(1000, 5);
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  CHECK_THROWS_AS(sem::icp(sem::Cloud{}, room, I), std::invalid_argument);
  CHECK_THROWS_AS(sem::icp(room, sem::Cloud{}, I), std::invalid_argument);
  sem::IcpSettings s;
  s.metric = sem::IcpMetric::PointToPlane;
  CHECK_THROWS_WITH(sem::icp(room, room, I, s), Catch::Contains("normal"));
  s = {};
  s.min_correspondence_m = 0.0;
  CHECK_THROWS_AS(sem::icp(room, room, I, s), std::invalid_argument);
  s = {};
  s.max_iterations = 0;
  CHECK_THROWS_AS(sem::icp(room, room, I, s), std::invalid_argument);
  s = {};
  s.coarse_stride = 0;
  CHECK_THROWS_WITH(sem::icp(room, room, I, s), Catch::Contains("coarse_stride"));
}

TEST_CASE("icp keeps the initial guess when nothing pairs within the distance", "[semantic]") {
  const sem::Cloud room = sem::test::synthetic_room(2000, 6);
  const Eigen::Isometry3d far = sem::test::pose(0, 0, 0, {100, 0, 0});
  const auto r = sem::icp(room, room, far);
  CHECK(r.inlier_ratio == 0.0);
  CHECK(!r.converged);
  CHECK(translation_error_m(r.T_target_source, far) < 1e-9);
}

TEST_CASE("correspondence distance shrinks from max to min over the first half", "[semantic]") {
  sem::IcpSettings s;
  s.max_iterations = 10;
  s.max_correspondence_m = 0.8;
  s.min_correspondence_m = 0.1;
  const auto r = sem::correspondence_schedule(s);
  REQUIRE(r.size() == 10);
  CHECK(r[0] == Approx(0.8));
  for (size_t i = 1; i < r.size(); ++i) CHECK(r[i] <= r[i - 1]);
  CHECK(r[4] > 0.1);
  CHECK(r[5] == Approx(0.1));
  CHECK(r[9] == Approx(0.1));
}

TEST_CASE("voxel grid finds the same nearest neighbour as brute force", "[semantic]") {
  const sem::Cloud room = sem::test::synthetic_room(5000, 7, 0.01);
  const sem::VoxelGrid grid(room.points, 0.2f);
  const sem::Cloud queries = sem::test::synthetic_room(500, 8, 0.05);
  std::vector<sem::VoxelGrid::Neighbour> knn;
  for (const auto& q : queries.points) {
    uint32_t best = sem::VoxelGrid::kNone;
    float best_d2 = 0.1f * 0.1f;
    std::vector<std::pair<float, uint32_t>> all;
    for (uint32_t i = 0; i < room.points.size(); ++i) {
      const float d2 = (room.points[i] - q).squaredNorm();
      all.push_back({d2, i});
      if (d2 <= best_d2) best_d2 = d2, best = i;
    }
    const auto nb = grid.nearest(q, 0.1f);
    REQUIRE(nb.index == best);
    // The clearance: a lower bound on every other point's distance (and at most the radius).
    float clear = -1.0f;
    const auto nc = grid.nearest_with_clearance(q, 0.1f, clear);
    REQUIRE(nc.index == best);
    CHECK(clear <= 0.1f);
    for (uint32_t i = 0; i < room.points.size(); ++i)
      if (i != best) REQUIRE(std::sqrt((room.points[i] - q).squaredNorm()) >= clear * (1.0f - 1e-6f));
    std::sort(all.begin(), all.end());
    grid.k_nearest(q, 8, knn, 6);
    REQUIRE(knn.size() == 8);
    for (size_t k = 0; k < 8; ++k) CHECK(knn[k].distance2_m2 == Approx(all[k].first).margin(1e-9));
  }
}

TEST_CASE("voxel grid's k nearest stop early only when no farther cell can hold a nearer point", "[semantic]") {
  // Small cells (a few points each): the 12th neighbour often lies one or
  // two rings out, where the early stop (ring + the query's gap to its own
  // cell's faces) decides; every answer must still be brute force's.
  const sem::Cloud room = sem::test::synthetic_room(5000, 9, 0.01);
  const sem::VoxelGrid grid(room.points, 0.08f);
  const sem::Cloud queries = sem::test::synthetic_room(300, 10, 0.03);
  std::vector<sem::VoxelGrid::Neighbour> knn;
  for (const auto& q : queries.points) {
    std::vector<float> all;
    for (const auto& p : room.points) all.push_back((p - q).squaredNorm());
    std::sort(all.begin(), all.end());
    grid.k_nearest(q, 12, knn, 8);
    REQUIRE(knn.size() == 12);
    for (size_t k = 0; k < 12; ++k) REQUIRE(knn[k].distance2_m2 == Approx(all[k]).margin(1e-9));
  }
}

TEST_CASE("voxel grid counts the cells a grid of the points occupies without building it", "[semantic]") {
  sem::Cloud room = sem::test::synthetic_room(4000, 11, 0.02);
  room.points.push_back(Eigen::Vector3f::Constant(std::nanf("")));  // left out, as the grid leaves it
  for (const float cell : {0.01f, 0.05f, 0.3f, 2.0f, 50.0f})
    CHECK(sem::VoxelGrid::count_cells(room.points, cell) == sem::VoxelGrid(room.points, cell).occupied_cells());
  CHECK(sem::VoxelGrid::count_cells({}, 0.1f) == 0);
  // With a limit: the count up to it, then limit + 1 and how far it read.
  const size_t all = sem::VoxelGrid::count_cells(room.points, 0.2f);
  size_t read = 0;
  CHECK(sem::VoxelGrid::count_cells(room.points, 0.2f, all, &read) == all);
  CHECK(read == room.size());
  CHECK(sem::VoxelGrid::count_cells(room.points, 0.2f, all / 2, &read) == all / 2 + 1);
  CHECK(read < room.size());
  CHECK(sem::VoxelGrid::count_cells(std::vector<Eigen::Vector3f>(room.points.begin(), room.points.begin() + static_cast<std::ptrdiff_t>(read)), 0.2f) == all / 2 + 1);
  CHECK_THROWS_AS(sem::VoxelGrid::count_cells(room.points, 0.0f), std::invalid_argument);
}

TEST_CASE("voxel grid numbers each point's cell in the grid's own order without building it", "[semantic]") {
  sem::Cloud room = sem::test::synthetic_room(4000, 12, 0.02);
  room.points.insert(room.points.begin() + 7, Eigen::Vector3f::Constant(std::nanf("")));  // no cell
  for (const float cell : {0.01f, 0.07f, 0.5f, 50.0f}) {
    INFO("cell " << cell);
    const sem::VoxelGrid grid(room.points, cell);
    size_t cells = 0;
    const std::vector<uint32_t> number = sem::VoxelGrid::cell_numbers(room.points, cell, cells);
    REQUIRE(number.size() == room.size());
    CHECK(cells == grid.occupied_cells());
    CHECK(number[7] == sem::VoxelGrid::kNone);
    // Cell k of the numbering is the grid's k-th run: the same points.
    const auto& offsets = grid.cell_offsets();
    const auto& index = grid.grid_index();
    bool same = true;
    for (size_t k = 0; k + 1 < offsets.size(); ++k)
      for (uint32_t j = offsets[k]; j < offsets[k + 1]; ++j) same = same && number[index[j]] == k;
    CHECK(same);
  }
  size_t cells = 0;
  CHECK(sem::VoxelGrid::cell_numbers({}, 0.1f, cells).empty());
  CHECK(cells == 0);
  CHECK_THROWS_AS(sem::VoxelGrid::cell_numbers(room.points, -1.0f, cells), std::invalid_argument);
}

TEST_CASE("voxel filter keeps one centroid per occupied cube", "[semantic]") {
  sem::Cloud c;
  c.points = {{0.01f, 0.01f, 0.01f}, {0.03f, 0.05f, 0.07f}, {0.15f, 0.0f, 0.0f}, {-0.05f, 0.0f, 0.0f}};
  const sem::Cloud f = sem::voxel_filter(c, 0.1);
  REQUIRE(f.size() == 3);
  bool found = false;
  for (const auto& p : f.points)
    if ((p - Eigen::Vector3f(0.02f, 0.03f, 0.04f)).norm() < 1e-6f) found = true;
  CHECK(found);
  CHECK_THROWS_AS(sem::voxel_filter(c, 0.0), std::invalid_argument);
}

TEST_CASE("estimate_normals finds the room's wall normals facing the viewpoint", "[semantic]") {
  sem::Cloud room = sem::test::synthetic_room(20000, 9);
  sem::estimate_normals(room, 10, Eigen::Vector3f(3, 2, 1.5));
  REQUIRE(room.normals.size() == room.points.size());
  size_t floor_points = 0, floor_up = 0;
  for (size_t i = 0; i < room.size(); ++i) {
    const auto& p = room.points[i];
    if (p.z() == 0.0f && p.x() > 0.3f && p.x() < 1.2f && p.y() > 0.3f && p.y() < 3.7f) {
      ++floor_points;
      if (room.normals[i].z() > 0.99f) ++floor_up;
    }
  }
  REQUIRE(floor_points > 100);
  CHECK(floor_up == floor_points);
}

TEST_CASE("estimate_normals_cells gives the room's floor and walls their normals, facing the viewpoint", "[semantic]") {
  sem::Cloud room = sem::test::synthetic_room(20000, 9);
  sem::estimate_normals_cells(room, 10, Eigen::Vector3f(3, 2, 1.5), 2);
  REQUIRE(room.normals.size() == room.points.size());
  // Away from edges by more than a cell's block (cells of ~5 points of a
  // surface here are ~17 cm): the floor's up, the wall at x = 0 along +x.
  size_t floor_points = 0, floor_up = 0, wall_points = 0, wall_in = 0;
  for (size_t i = 0; i < room.size(); ++i) {
    const auto& p = room.points[i];
    const bool clear_y = p.y() > 0.5f && p.y() < 3.5f;
    if (p.z() == 0.0f && p.x() > 0.5f && p.x() < 1.0f && clear_y) {
      ++floor_points;
      if (room.normals[i].z() > 0.99f) ++floor_up;
    }
    if (p.x() == 0.0f && p.z() > 0.5f && p.z() < 2.5f && clear_y) {
      ++wall_points;
      if (room.normals[i].x() > 0.99f) ++wall_in;
    }
  }
  REQUIRE(floor_points > 50);
  REQUIRE(wall_points > 100);
  CHECK(floor_up == floor_points);
  CHECK(wall_in == wall_points);
  // The same normals on one thread, and a bad k refused.
  sem::Cloud again = sem::test::synthetic_room(20000, 9);
  sem::estimate_normals_cells(again, 10, Eigen::Vector3f(3, 2, 1.5), 1);
  CHECK(again.normals == room.normals);
  CHECK_THROWS_AS(sem::estimate_normals_cells(again, 2), std::invalid_argument);
}
