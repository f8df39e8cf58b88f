// Doors, windows and obstacles on small synthetic clouds (points sampled on
// surfaces, 2 cm apart, 5 mm noise) and on PCL's real room scan.

#include <catch2/catch.hpp>

#include <random>

#include "semantic/cloud_io.hpp"
#include "semantic/segmentation.hpp"
#include "tests/test_data.hpp"

using namespace rise::semantic;

namespace {

constexpr double kStep = 0.02;

// An 8 x 6 m floor at z = 0, points 2 cm apart.
Cloud bare_floor() {
  Cloud c;
  for (double x = -4; x <= 4; x += kStep)
    for (double y = -3; y <= 3; y += kStep) c.points.emplace_back(static_cast<float>(x), static_cast<float>(y), 0.0f);
  return c;
}

// A box x0..x1, y0..y1 standing on the floor, h high: its top and its faces along x.
void add_box(Cloud& c, double x0, double x1, double y0, double y1, double h) {
  for (double x = x0; x <= x1; x += kStep)
    for (double y = y0; y <= y1; y += kStep) c.points.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(h));
  for (double z = 0; z <= h; z += kStep)
    for (double x = x0; x <= x1; x += kStep)
      for (const double y : {y0, y1}) c.points.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
}

// A 6 m wall along x at y = 0, 15 cm thick, 2.5 m high, with the floor on
// both sides (or before it only), and what fills the gap x = -0.45..0.45
// (a window: from sill_m to 2 m; a ledge: a window's sill seen from above
// only, at sill_m, clear of the faces' planes).
enum class Gap { Doorway, Window, Ledge, ClosedDoor, Shadow };

Cloud wall_with(Gap gap, double sill_m = 0.9) {
  Cloud c;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.005);
  const auto add = [&](double x, double y, double z) {
    c.points.emplace_back(static_cast<float>(x + noise(rng)), static_cast<float>(y + noise(rng)),
                          static_cast<float>(z + noise(rng)));
  };
  const bool both_sides = gap != Gap::Shadow;
  // The floor: in front of the wall (y < 0), and behind it unless the wall hides it.
  for (double x = -3; x <= 3; x += kStep)
    for (double y = -3; y <= 3; y += kStep)
      if (y < -0.1 || (both_sides && y > 0.1) || (gap == Gap::Doorway && std::abs(x) < 0.45)) add(x, y, 0);
  // The faces, y = ±0.075, but for the gap.
  const auto in_gap = [&](double x, double z) {
    if (std::abs(x) >= 0.45) return false;
    switch (gap) {
      case Gap::Window: return z > sill_m && z < 2.0;
      default: return z < 2.0;
    }
  };
  for (const double y : {-0.075, 0.075}) {
    if (y > 0 && !both_sides) continue;
    for (double x = -3; x <= 3; x += kStep)
      for (double z = 0; z <= 2.5; z += kStep)
        if (!in_gap(x, z)) add(x, y, z);
  }
  // The lintel's underside and, for a window, the sill's top.
  for (double x = -0.45; x <= 0.45; x += kStep)
    for (double y = -0.075; y <= 0.075; y += kStep) {
      add(x, y, 2.0);
      if (gap == Gap::Window || (gap == Gap::Ledge && std::abs(y) < 0.04)) add(x, y, sill_m);
    }
  if (gap == Gap::ClosedDoor)  // the leaf, in the middle of the wall
    for (double x = -0.44; x <= 0.44; x += kStep)
      for (double z = 0.01; z <= 1.99; z += kStep) add(x, 0.0, z);
  return c;
}

}  // namespace

TEST_CASE("an open doorway in a wall is a door: lintel above, the floor seen through it", "[semantic]") {
  const Segmentation seg = segment(wall_with(Gap::Doorway));
  REQUIRE(seg.doors.size() == 1);
  const Door& d = seg.doors[0];
  CHECK(d.lintel);
  CHECK_FALSE(d.panel);
  CHECK(d.center_m.norm() < 0.1);
  CHECK(d.width_m == Approx(0.9).margin(0.1));
  CHECK(d.height_m == Approx(2.0).margin(0.1));
}

TEST_CASE("a closed door in a wall is a door with its panel", "[semantic]") {
  const Segmentation seg = segment(wall_with(Gap::ClosedDoor));
  REQUIRE(seg.doors.size() == 1);
  CHECK(seg.doors[0].panel);
  CHECK(seg.doors[0].center_m.norm() < 0.1);
  CHECK(seg.doors[0].width_m == Approx(0.9).margin(0.1));
}

TEST_CASE("a window (a sill across the gap) and a shadow in a face are not doors", "[semantic]") {
  SECTION("a window, sill at 0.9 m") {
    const Segmentation seg = segment(wall_with(Gap::Window));
    CHECK(seg.doors.empty());
    CHECK_FALSE(seg.walls.empty());
  }
  SECTION("a window's sill seen from above only, below the wall band, the floor seen beyond it") {
    // (A sill in the wall band makes the faces' cells tall: no gap at all.)
    SegmentationSettings s;
    s.wall_band_margin_m = 0.5;
    CHECK(segment(wall_with(Gap::Ledge, 0.4), s).doors.empty());
    CHECK(segment(wall_with(Gap::Doorway), s).doors.size() == 1);
  }
  SECTION("a gap in the one face seen, the floor seen only in front of it") {
    const Segmentation seg = segment(wall_with(Gap::Shadow));
    CHECK(seg.doors.empty());
  }
}

TEST_CASE("nothing larger than obstacle_max_size_m is an obstacle: a long counter is dropped and counted", "[semantic]") {
  Cloud c = bare_floor();
  // A 5 m counter, 0.6 x 0.9 m, and a 0.5 m box 1.5 m from it.
  add_box(c, -2.5, 2.5, -2.0, -1.4, 0.9);
  add_box(c, 0.0, 0.5, 0.1, 0.6, 0.5);
  const Segmentation seg = segment(c);
  REQUIRE(seg.obstacles.size() == 1);
  CHECK(seg.obstacles[0].size_m.head<2>().maxCoeff() == Approx(0.5).margin(0.05));
  CHECK(seg.oversize_clusters_dropped == 1);
  SegmentationSettings wide;
  wide.obstacle_max_size_m = 6.0;
  CHECK(segment(c, wide).obstacles.size() == 2);
}

TEST_CASE("PCL's real room scan: no obstacle is larger than 3 m (it was 9.8 x 11.3 m)", "[semantic]") {
  const std::string file = rise::test::data_file("pointclouds/PointCloudLibrary_data/room_scan1.pcd");
  if (file.empty()) {
    WARN("skipped: RISE_TEST_DATA/pointclouds/PointCloudLibrary_data/room_scan1.pcd is absent");
    return;
  }
  const Segmentation seg = segment(read_cloud(file));
  CHECK(seg.floor.height_m == Approx(-1.27).margin(0.05));
  CHECK(seg.walls.size() >= 4);
  CHECK_FALSE(seg.obstacles.empty());
  for (const auto& o : seg.obstacles) {
    INFO("obstacle at " << o.center_m.transpose() << " size " << o.size_m.transpose());
    CHECK(o.size_m.maxCoeff() <= 3.0);
  }
}

TEST_CASE("no obstacle box shuts a doorway its points leave open; a thing standing in it stays", "[semantic]") {
  // Beyond the doorway's wall (y > 0): a band at the lintel's height just
  // clear of the wall (y = 0.2, z 2.0-2.4; the real room's far face and
  // lintel leak so) and a cabinet beside the doorway: one cluster, whose
  // box would cover the doorway's far side.
  Cloud c = wall_with(Gap::Doorway);
  for (double x = -1.5; x <= 1.3; x += kStep)
    for (double z = 2.0; z <= 2.4; z += kStep) c.points.emplace_back(static_cast<float>(x), 0.2f, static_cast<float>(z));
  add_box(c, 0.7, 1.3, 0.2, 0.8, 1.0);
  const auto passage_covered = [](const Segmentation& seg) {
    for (const Obstacle& o : seg.obstacles) {
      const Eigen::Vector2d ax(std::cos(o.yaw_rad), std::sin(o.yaw_rad)), ay(-ax.y(), ax.x());
      for (double u = -0.5; u <= 0.5; u += 0.05)
        for (double v = -0.5; v <= 0.5; v += 0.05) {
          const Eigen::Vector2d p = o.center_m.head<2>() + u * o.size_m.x() * ax + v * o.size_m.y() * ay;
          if (std::abs(p.x()) < 0.4 && std::abs(p.y()) < 0.9) return true;
        }
    }
    return false;
  };
  SECTION("the band and the cabinet") {
    const Segmentation seg = segment(c);
    REQUIRE(seg.doors.size() == 1);
    CHECK_FALSE(passage_covered(seg));
    CHECK(seg.oversize_clusters_dropped >= 1);
  }
  SECTION("and a chair in the doorway") {
    add_box(c, -0.2, 0.2, 0.4, 0.8, 0.8);
    const Segmentation seg = segment(c);
    REQUIRE(seg.doors.size() == 1);
    CHECK(passage_covered(seg));
  }
}
