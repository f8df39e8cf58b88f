#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <map>

#include "sim/laser_scanner.hpp"
#include "sim/simulation.hpp"
#include "tests/sim/sim_panel.hpp"
#include "tests/sim/world_geometry.hpp"

using namespace rise::sim;
using rise::sim::testing::nearest_surface;
using rise::sim::testing::world_solids;

namespace {
const std::string kTracked = std::string(RISE_SOURCE_DIR) + "/sim/robots/tracked_eod.yaml";
const std::string kBuilding = std::string(RISE_SOURCE_DIR) + "/sim/worlds/building.yaml";
constexpr double kDeg = M_PI / 180.0;

// A closed room of four static boxes around the origin; inner faces at
// x = -3 and 4, y = -2 and 2.5, all 2 m high.
WorldDescription box_room() {
  WorldDescription w;
  w.name = "box_room";
  w.boxes.push_back({"east", {4.1, 0.0, 1.0}, {0.2, 10.0, 2.0}, 0.0});
  w.boxes.push_back({"west", {-3.1, 0.0, 1.0}, {0.2, 10.0, 2.0}, 0.0});
  w.boxes.push_back({"north", {0.0, 2.6, 1.0}, {10.0, 0.2, 2.0}, 0.0});
  w.boxes.push_back({"south", {0.0, -2.1, 1.0}, {10.0, 0.2, 2.0}, 0.0});
  return w;
}

// A horizontal 360° line scanner, 1° steps, 0.25 m ahead of the chassis centre.
LaserDescription ring_scanner(double noise_m) {
  LaserDescription l;
  l.mount.position_m = {0.25, 0.0, 0.17};
  l.fov_rad = 2 * M_PI;
  l.resolution_rad = 1.0 * kDeg;
  l.min_range_m = 0.1;
  l.max_range_m = 30.0;
  l.noise_m = noise_m;
  return l;
}

// Distance from (x0, y0) along angle a to the box room's inner faces.
double room_range_m(double x0, double y0, double a) {
  const double c = std::cos(a), s = std::sin(a);
  double r = std::numeric_limits<double>::infinity();
  if (c > 1e-12) r = std::min(r, (4.0 - x0) / c);
  if (c < -1e-12) r = std::min(r, (-3.0 - x0) / c);
  if (s > 1e-12) r = std::min(r, (2.5 - y0) / s);
  if (s < -1e-12) r = std::min(r, (-2.0 - y0) / s);
  return r;
}

RobotDescription tracked_without_noise() {
  auto robot = load_robot_description(kTracked);
  robot.sensors.laser->noise_m = 0.0;
  return robot;
}
}  // namespace

TEST_CASE("the robot file's laser is a rotating 2D scanner of 361 beams in 180 lines", "[sim]") {
  const auto robot = load_robot_description(kTracked);
  REQUIRE(robot.sensors.laser.has_value());
  const auto& l = *robot.sensors.laser;
  CHECK(l.beams() == 361);
  CHECK(l.lines() == 180);
  CHECK(l.max_range_m == Approx(30.0).margin(1e-12));
  CHECK(l.noise_m == Approx(0.01).margin(1e-12));
  REQUIRE(l.rotating.has_value());
  CHECK(l.rotating->axis == 1);
  CHECK(l.rotating->angle_rad(90) == Approx(M_PI).margin(1e-12));
  REQUIRE(robot.sensors.cameras.size() == 2);
  CHECK(robot.sensors.cameras[1].name == "chase");
}

TEST_CASE("a wrong sensors section is refused with file:line and the key", "[sim]") {
  const std::string base = "robot: r\nchassis: {}\nwheels: {}\ncontrol: {linear: {axis: y, max_mps: 1}, angular: {axis: x, max_radps: 1}}\n";
  struct Case {
    const char* sensors;
    const char* expected;
  };
  const auto c = GENERATE(
      Case{"sensors:\n  laser: {mount_m: [0, 0, 0], fov_deg: 400}\n", "bad.yaml:6: sensors.laser.fov_deg: must be <= 360"},
      Case{"sensors:\n  laser: {mount_m: [0, 0]}\n", "bad.yaml:6: sensors.laser.mount_m: expected [x, y, z]"},
      Case{"sensors:\n  laser: {mount_m: [0, 0, 0], range_m: [5, 1]}\n",
           "bad.yaml:6: sensors.laser.range_m: expected [min, max] with 0 <= min < max"},
      Case{"sensors:\n  laser: {mount_m: [0, 0, 0], rotating: {axis: w, steps: 10}}\n",
           "bad.yaml:6: sensors.laser.rotating.axis: expected x, y or z"},
      Case{"sensors:\n  laser: {mount_m: [0, 0, 0], noise: 0.1}\n", "bad.yaml:6: sensors.laser.noise: unknown key"},
      Case{"sensors:\n  imu: {gyro_noise_radps: -1}\n", "bad.yaml:6: sensors.imu.gyro_noise_radps: must be >= 0"},
      Case{"sensors:\n  cameras:\n    - {name: a, mount_m: [0, 0, 0]}\n    - {name: a, mount_m: [1, 0, 0]}\n",
           "bad.yaml:8: sensors.cameras[1].name: duplicate camera 'a'"});
  std::string error = "no error";
  try {
    parse_robot_description(base + c.sensors, "bad.yaml");
  } catch (const std::runtime_error& e) {
    error = e.what();
  }
  CHECK(error == c.expected);
}

TEST_CASE("ranges in a box room equal the hand-computed distances within 1 mm", "[sim]") {
  Simulation sim(tracked_without_noise(), box_room());
  LaserScanner scanner(ring_scanner(0.0), 1);
  const LaserScan scan = scanner.scan(sim);
  // Before the first step the chassis sits exactly at its build pose: the
  // origin, facing +x, so the sensor is at (0.25, 0).
  const Eigen::Vector3d origin = scan.T_world_sensor.translation();
  CHECK(origin.x() == Approx(0.25).margin(1e-9));
  CHECK(origin.y() == Approx(0.0).margin(1e-9));
  REQUIRE(scan.beams == 360);
  REQUIRE(scan.lines == 1);
  REQUIRE(scan.points_world.size() == 360);
  double worst = 0.0;
  for (int i = 0; i < scan.beams; ++i) {
    const double expected = room_range_m(0.25, 0.0, -M_PI + i * kDeg);
    const double got = scan.ranges_m[static_cast<std::size_t>(i)];
    worst = std::max(worst, std::fabs(got - expected));
  }
  INFO("worst range error " << worst * 1000 << " mm");
  CHECK(worst < 0.001);
  // Every point lies on the room's faces (horizontal scan: at the sensor's height).
  for (const auto& p : scan.points_world) {
    const double face = std::min({std::fabs(p.x() - 4.0), std::fabs(p.x() + 3.0), std::fabs(p.y() - 2.5),
                                  std::fabs(p.y() + 2.0)});
    CHECK(face < 0.001);
    CHECK(p.z() == Approx(origin.z()).margin(1e-5));
  }
}

TEST_CASE("range noise has the configured sigma and no bias", "[sim]") {
  constexpr double kSigma = 0.02;
  Simulation sim(tracked_without_noise(), box_room());
  LaserScanner scanner(ring_scanner(kSigma), 7);
  double sum = 0.0, sum2 = 0.0;
  int n = 0;
  for (int k = 0; k < 30; ++k) {
    const LaserScan scan = scanner.scan(sim);
    for (int i = 0; i < scan.beams; ++i) {
      const double e = scan.ranges_m[static_cast<std::size_t>(i)] - room_range_m(0.25, 0.0, -M_PI + i * kDeg);
      sum += e;
      sum2 += e * e;
      ++n;
    }
  }
  REQUIRE(n == 30 * 360);
  const double mean = sum / n;
  const double sd = std::sqrt(sum2 / n - mean * mean);
  // Sampling spread: σ/√n ≈ 0.19 mm for the mean, ≈ 0.7 % for σ; margins ~5x that.
  CHECK(mean == Approx(0.0).margin(0.001));
  CHECK(sd == Approx(kSigma).epsilon(0.04));
}

TEST_CASE("the same seed gives the same scan bit for bit, another seed another", "[sim]") {
  const auto scan_with = [](uint64_t seed) {
    Simulation sim(load_robot_description(kTracked), load_world_description(kBuilding));
    rise::sim::testing::run_for(sim, 0.2);
    LaserScanner scanner(*sim.robot().sensors.laser, seed);
    return scanner.scan(sim);
  };
  const LaserScan a = scan_with(5), b = scan_with(5), c = scan_with(6);
  REQUIRE(a.ranges_m.size() == b.ranges_m.size());
  CHECK(std::memcmp(a.ranges_m.data(), b.ranges_m.data(), a.ranges_m.size() * sizeof(float)) == 0);
  REQUIRE(a.points_world.size() == b.points_world.size());
  CHECK(std::memcmp(a.points_world.data(), b.points_world.data(), a.points_world.size() * sizeof(Eigen::Vector3f)) == 0);
  CHECK(a.T_world_sensor.matrix() == b.T_world_sensor.matrix());
  REQUIRE(c.ranges_m.size() == a.ranges_m.size());
  CHECK(std::memcmp(a.ranges_m.data(), c.ranges_m.data(), a.ranges_m.size() * sizeof(float)) != 0);
}

TEST_CASE("the 3D scan of the building has its walls where the world file puts them", "[sim]") {
  const WorldDescription world = load_world_description(kBuilding);
  Simulation sim(tracked_without_noise(), world);
  rise::sim::testing::run_for(sim, 0.5);  // settled on its tracks
  LaserScanner scanner(*sim.robot().sensors.laser, 1);
  const LaserScan scan = scanner.scan(sim);
  REQUIRE(scan.ranges_m.size() == 361u * 180u);
  REQUIRE(scan.points_world.size() > 40000);

  const auto solids = world_solids(world);
  const Eigen::Vector3d origin = scan.T_world_sensor.translation();
  std::map<std::string, int> hits;
  std::map<std::string, double> worst;
  int inside = 0, too_far = 0;
  for (const auto& pf : scan.points_world) {
    const Eigen::Vector3d p = pf.cast<double>();
    const auto n = nearest_surface(solids, p);
    ++hits[n.name];
    worst[n.name] = std::max(worst[n.name], n.distance_m);
    for (const auto& s : solids)
      if (s.signed_distance_m(p) < -0.001) ++inside;
    if ((p - origin).norm() > scanner.description().max_range_m) ++too_far;
  }
  CHECK(inside == 0);
  CHECK(too_far == 0);
  // Each point is on the surface of the solid it is nearest to (ground: z = 0).
  for (const auto& [name, d] : worst) {
    INFO(name << ": " << hits[name] << " points, worst distance to its surface " << d * 1000 << " mm");
    CHECK(d < 0.001);
  }
  // Everything the start in room A sees: its six walls, the closed door,
  // the corridor's north wall through the open doorway, the floor and the
  // ceiling (its points on the slab's underside, z = 2.6 m).
  for (const char* name : {"wall_south", "wall_west", "wall_a_corridor_w", "wall_a_corridor_e", "wall_ab_south",
                           "wall_ab_north", "door_ab", "wall_north", "ground", "ceiling"}) {
    INFO(name);
    CHECK(hits[name] >= 100);
  }
  // Room B's walls and the staircase are hidden behind room A's walls.
  CHECK(hits["wall_east"] == 0);
  CHECK(hits["staircase"] == 0);
  // Ranges and sensor-frame points agree with the world points through the true pose.
  std::size_t k = 0;
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    if (std::isnan(scan.ranges_m[i])) continue;
    CHECK(scan.points_sensor[k].norm() == Approx(scan.ranges_m[i]).margin(1e-4));
    if (k % 997 == 0)
      CHECK((scan.T_world_sensor * scan.points_sensor[k].cast<double>() - scan.points_world[k].cast<double>()).norm() <
            1e-4);
    ++k;
  }
  CHECK(k == scan.points_world.size());
}

TEST_CASE("the robot's own parts never return a laser point", "[sim]") {
  // Nothing but the robot and the floor within 1 m: a vertical full-circle
  // scanner on the chassis sees only the floor.
  Simulation sim(tracked_without_noise(), WorldDescription{});
  LaserDescription l = ring_scanner(0.0);
  l.mount.rpy_rad = {M_PI / 2, 0.0, 0.0};  // scan plane vertical, along the robot: down through the chassis, up through the arm
  l.max_range_m = 1.0;
  LaserScanner scanner(l, 1);
  const LaserScan scan = scanner.scan(sim);
  REQUIRE(!scan.points_world.empty());
  for (const auto& p : scan.points_world) CHECK(std::fabs(p.z()) < 1e-4);
}

TEST_CASE("a camera mount's world pose follows the robot", "[sim]") {
  Simulation sim(load_robot_description(kTracked), WorldDescription{});
  sim.set_input(rise::sim::testing::drive_panel(1.0f, 0.0f));
  rise::sim::testing::run_for(sim, 2.0);
  const auto front = sim.T_world_camera("front");
  REQUIRE(front.has_value());
  const Eigen::Isometry3d expected = sim.T_world_base() * sim.robot().sensors.cameras[0].mount.T_base_mount();
  CHECK((front->matrix() - expected.matrix()).norm() < 1e-12);
  CHECK(front->translation().x() > 1.0);  // it moved with the robot
  // 10° down: the optical (x) axis points below the horizon.
  CHECK(front->linear().col(0).z() == Approx(-std::sin(10 * kDeg)).margin(0.02));
  CHECK_FALSE(sim.T_world_camera("nope").has_value());
}
