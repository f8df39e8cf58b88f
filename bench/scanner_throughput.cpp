// Laser scanner throughput on one core: rays per second for 3D scans of the
// building (sim/worlds/building.yaml) by the tracked EOD robot's rotating
// scanner (sim/robots/tracked_eod.yaml: 361 beams × 180 lines) from its
// start in room A, plus the accuracy of the noise-free scan: the worst
// distance of a point from the world file's surface it is nearest to
// (tests/sim/world_geometry.hpp), per wall. No peer is named: the figure is
// the project's own, to compare against itself.
//
// Usage: bench_scanner_throughput [scans=10]

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "sim/laser_scanner.hpp"
#include "sim/simulation.hpp"
#include "tests/sim/world_geometry.hpp"

int main(int argc, char** argv) {
  const int scans = argc > 1 ? std::max(1, std::atoi(argv[1])) : 10;
  const std::string root = RISE_SOURCE_DIR;
  auto robot = rise::sim::load_robot_description(root + "/sim/robots/tracked_eod.yaml");
  const auto world = rise::sim::load_world_description(root + "/sim/worlds/building.yaml");
  rise::sim::Simulation sim(robot, world);
  for (int i = 0; i < 500; ++i) sim.step();

  rise::sim::LaserScanner scanner(*robot.sensors.laser, robot.sensors.seed);
  std::vector<double> times_s;
  std::size_t rays = 0, points = 0;
  for (int k = 0; k < scans; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto scan = scanner.scan(sim);
    times_s.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    rays = scan.ranges_m.size();
    points = scan.points_world.size();
  }
  std::sort(times_s.begin(), times_s.end());
  const double median_s = times_s[times_s.size() / 2];
  std::printf("3D scan of the building: %zu rays (%d beams x %d lines), %zu returns\n", rays,
              robot.sensors.laser->beams(), robot.sensors.laser->lines(), points);
  std::printf("scan time: median %.1f ms, best %.1f ms, worst %.1f ms over %d scans (one core)\n", median_s * 1e3,
              times_s.front() * 1e3, times_s.back() * 1e3, scans);
  std::printf("throughput: %.2f Mrays/s (median)\n", static_cast<double>(rays) / median_s / 1e6);

  auto exact_laser = *robot.sensors.laser;
  exact_laser.noise_m = 0.0;
  rise::sim::LaserScanner exact(exact_laser, 1);
  const auto scan = exact.scan(sim);
  const auto solids = rise::sim::testing::world_solids(world);
  std::map<std::string, std::pair<int, double>> per;  // name → points, worst distance
  for (const auto& p : scan.points_world) {
    const auto n = rise::sim::testing::nearest_surface(solids, p.cast<double>());
    auto& e = per[n.name];
    ++e.first;
    e.second = std::max(e.second, n.distance_m);
  }
  std::printf("noise-free scan, worst distance from the surface each point is nearest to:\n");
  for (const auto& [name, e] : per) std::printf("  %-20s %6d points  %.2e mm\n", name.c_str(), e.first, e.second * 1e3);
  return 0;
}
