#include <catch2/catch.hpp>

#include <cmath>
#include <iostream>
#include <cstdlib>
#include <filesystem>

#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include "semantic/segmentation.hpp"
#include "sim/world_description.hpp"
#include "tests/semantic/building_cloud.hpp"
#include "tests/semantic/ground_truth.hpp"

using namespace rise::semantic;
using namespace rise::semantic::testing;

namespace {
constexpr double kDeg = M_PI / 180.0;

const Segmentation& building_segmentation() {
  static const Segmentation seg = segment(building_cloud());
  return seg;
}

double angle_between(double a, double b) {
  return std::abs(std::remainder(a - b, 2 * M_PI));
}
}  // namespace

TEST_CASE("the building's floor and ceiling heights are found within 2 cm", "[semantic]") {
  const auto& seg = building_segmentation();
  CHECK(seg.floor.height_m == Approx(0.0).margin(0.02));
  CHECK(seg.floor.normal.z() > std::cos(1 * kDeg));
  REQUIRE(seg.ceiling.found);
  CHECK(seg.ceiling.height_m == Approx(2.6).margin(0.02));
}

TEST_CASE("the building's walls are found within 5 cm and 2 degrees with precision and recall of 0.95", "[semantic]") {
  const auto world = rise::sim::load_world_description(kBuilding);
  const auto& seg = building_segmentation();
  const WallScore s = score_walls(world.walls, seg.walls);
  INFO(s.report);
  INFO(s.found << " walls found, " << s.precise << " precise; " << s.recalled << " of " << s.truth << " recalled");
  CHECK(s.precision() >= 0.95);
  CHECK(s.recall() >= 0.95);
  for (const auto& w : seg.walls) {
    INFO("wall (" << w.from_m.transpose() << ") - (" << w.to_m.transpose() << ")");
    CHECK(w.height_m == Approx(2.5).margin(0.03));
    CHECK(w.thickness_m == Approx(0.15).margin(0.02));
  }
}

TEST_CASE("every door of the building is found within 10 cm, with its width and height", "[semantic]") {
  const auto world = rise::sim::load_world_description(kBuilding);
  const auto& seg = building_segmentation();
  const auto truth = truth_doors(world);
  REQUIRE(truth.size() == 2);
  CHECK(seg.doors.size() == truth.size());
  for (const auto& t : truth) {
    INFO(t.name);
    const Door* best = nullptr;
    for (const auto& d : seg.doors)
      if (!best || (d.center_m - t.center).norm() < (best->center_m - t.center).norm()) best = &d;
    REQUIRE(best != nullptr);
    CHECK((best->center_m - t.center).norm() < 0.10);
    CHECK(best->width_m == Approx(t.width_m).margin(0.10));
    CHECK(best->height_m == Approx(t.height_m).margin(0.10));
  }
}

TEST_CASE("the building's staircase is found with its step count, riser and tread within 1 cm", "[semantic]") {
  const auto world = rise::sim::load_world_description(kBuilding);
  const auto& seg = building_segmentation();
  REQUIRE(seg.stairs.size() == 1);
  const auto& t = world.stairs.front();
  const auto& s = seg.stairs.front();
  CHECK(s.steps == t.steps);
  CHECK(s.riser_m == Approx(t.riser_m).margin(0.01));
  CHECK(s.tread_m == Approx(t.tread_m).margin(0.01));
  CHECK(angle_between(s.yaw_rad, t.yaw_rad) < 2 * kDeg);
  CHECK((s.start_m - v2(t.start_m)).norm() < 0.05);
  CHECK(s.width_m == Approx(t.width_m).margin(0.05));
  CHECK(s.landing_m == Approx(t.landing_m).margin(0.10));
}

TEST_CASE("the object in room B is a static obstacle box", "[semantic]") {
  const auto world = rise::sim::load_world_description(kBuilding);
  const auto& seg = building_segmentation();
  const auto& o = world.objects.front();
  const Obstacle* best = nullptr;
  for (const auto& b : seg.obstacles)
    if (!best || (b.center_m.head<2>() - Eigen::Vector2d(o.center_m[0], o.center_m[1])).norm() <
                     (best->center_m.head<2>() - Eigen::Vector2d(o.center_m[0], o.center_m[1])).norm())
      best = &b;
  REQUIRE(best != nullptr);
  CHECK((best->center_m.head<2>() - Eigen::Vector2d(o.center_m[0], o.center_m[1])).norm() < 0.1);
  CHECK(best->size_m.z() == Approx(0.3).margin(0.05));
  CHECK(seg.obstacles.size() <= 2);
}

TEST_CASE("dump", "[.dump]") {
  const auto& seg = building_segmentation();
  std::cout << "cloud " << building_cloud().size() << " floor " << seg.floor.height_m << " ceil " << seg.ceiling.height_m << "\n";
  for (const auto& w : seg.walls) {
    std::cout << "wall " << w.from_m.transpose() << " -> " << w.to_m.transpose() << " h " << w.height_m << " t " << w.thickness_m << " both " << w.both_faces_seen << " n " << w.points;
    for (const auto& o : w.openings) std::cout << " [open " << o.at_m << " " << o.width_m << " " << o.height_m << "]";
    std::cout << "\n";
  }
  for (const auto& d : seg.doors) std::cout << "door " << d.center_m.transpose() << " w " << d.width_m << " h " << d.height_m << " lintel " << d.lintel << " panel " << d.panel << "\n";
  for (const auto& s : seg.stairs) std::cout << "stairs " << s.start_m.transpose() << " yaw " << s.yaw_rad << " n " << s.steps << " r " << s.riser_m << " t " << s.tread_m << " w " << s.width_m << " l " << s.landing_m << "\n";
  for (const auto& o : seg.obstacles) std::cout << "obst " << o.center_m.transpose() << " size " << o.size_m.transpose() << " yaw " << o.yaw_rad << " n " << o.points << "\n";
}
TEST_CASE("dump2", "[.dump2]") {
  const auto& c = building_cloud();
  int n = 0, nz = 0;
  for (const auto& p : c.points) if (p.x() > 0.5 && p.x() < 3.6 && p.y() > 3.7 && p.y() < 4.8) { ++n; if (p.z() > 0.05) ++nz; }
  std::cout << "stairs box points " << n << " above floor " << nz << "\n";
  for (const auto& pose : building_poses()) {
    auto w = rise::sim::load_world_description(kBuilding);
    auto one = scan_world(w, {pose}, 1);
    std::cout << pose[0] << "," << pose[1] << ": " << one.size() << "\n";
  }
}
