// Several robots in one world: each follows its own panel, they collide with
// each other (events name both robots' parts), and the world stays
// deterministic bit for bit.

#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "sim/simulation.hpp"
#include "tests/sim/sim_panel.hpp"

using namespace rise::sim;
using rise::sim::testing::drive_panel;
using rise::sim::testing::run_for;

namespace {
const std::string kRobots = std::string(RISE_SOURCE_DIR) + "/sim/robots/";

RobotSpec spec(const std::string& id, const std::string& robot, double x, double y, double yaw_deg) {
  return RobotSpec{id, load_robot_description(kRobots + robot + ".yaml"), RobotStart{{x, y}, yaw_deg * M_PI / 180.0}};
}

double travelled_m(const RobotSnapshot& s, double x0, double y0) {
  return std::hypot(s.position_m[0] - x0, s.position_m[1] - y0);
}

ControlInput idle_panel() {
  ControlInput in = drive_panel(0.0f, 0.0f);
  in.deadman = false;
  return in;
}
}  // namespace

TEST_CASE("two robots in one world each follow only their own panel", "[sim]") {
  std::vector<RobotSpec> robots{spec("alpha", "skid4", 0.0, 0.0, 0.0), spec("bravo", "tracked_eod", 0.0, 3.0, 90.0)};
  Simulation sim(robots, WorldDescription{});
  REQUIRE(sim.robot_count() == 2);
  CHECK(sim.robot_id(1) == "bravo");
  CHECK(sim.robot_index("alpha") == 0);
  CHECK_THROWS_AS(sim.robot_index("charlie"), std::out_of_range);
  CHECK(sim.snapshot(1).position_m[1] == Approx(3.0).margin(1e-9));  // its own start pose
  CHECK(sim.snapshot(1).yaw_rad() == Approx(M_PI / 2).margin(1e-9));

  // Alpha drives, bravo's dead-man is released.
  sim.set_input(0, drive_panel(1.0f, 0.0f));
  sim.set_input(1, idle_panel());
  run_for(sim, 2.0);
  auto a = sim.snapshot(0), b = sim.snapshot(1);
  INFO("alpha at " << a.position_m[0] << ", " << a.position_m[1] << "; bravo at " << b.position_m[0] << ", "
                   << b.position_m[1]);
  CHECK(a.position_m[0] > 1.8);
  CHECK(a.motors_enabled);
  CHECK(travelled_m(b, 0.0, 3.0) < 0.02);
  CHECK_FALSE(b.motors_enabled);
  CHECK(b.stop_reason == "dead-man released");

  // Now bravo drives (north, its heading), alpha stops.
  const double ax = a.position_m[0], ay = a.position_m[1];
  sim.set_input(0, idle_panel());
  sim.set_input(1, drive_panel(1.0f, 0.0f));
  run_for(sim, 2.0);
  a = sim.snapshot(0);
  b = sim.snapshot(1);
  CHECK(travelled_m(a, ax, ay) < 0.35);  // braking from 1.2 m/s
  CHECK(a.speed_mps() < 0.01);
  CHECK(b.position_m[1] > 3.0 + 1.2);
  CHECK(std::fabs(b.position_m[0]) < 0.1);
  CHECK(b.odometry.position_m[1] > 3.0 + 1.0);  // its odometry starts at its own start pose
  // Far apart: no collisions between them, and each robot's contacts are its own.
  for (const auto& e : sim.take_events()) CHECK(e.kind != SimEventKind::CollisionStarted);
  CHECK(a.contacts.empty());
  CHECK(b.contacts.empty());
}

TEST_CASE("a robot driving into another reports the collision with both robots' parts", "[sim]") {
  // Alpha faces bravo's left side, 2.5 m ahead.
  std::vector<RobotSpec> robots{spec("alpha", "skid4", 0.0, 0.0, 0.0), spec("bravo", "tracked_eod", 2.5, 0.0, 90.0)};
  Simulation sim(robots, WorldDescription{});
  sim.set_input(0, drive_panel(0.5f, 0.0f));
  sim.set_input(1, idle_panel());
  std::vector<SimEvent> log;
  bool alpha_sees_bravo = false, bravo_sees_alpha = false;
  double closest_m = 10.0;  // alpha's centre to bravo's
  for (int i = 0; i < 6000; ++i) {
    sim.step();
    for (auto& e : sim.take_events()) log.push_back(std::move(e));
    closest_m = std::min(closest_m, sim.snapshot(1).position_m[0] - sim.snapshot(0).position_m[0]);
    for (const auto& c : sim.snapshot(0).contacts) alpha_sees_bravo = alpha_sees_bravo || c.rfind("bravo/", 0) == 0;
    for (const auto& c : sim.snapshot(1).contacts) bravo_sees_alpha = bravo_sees_alpha || c.rfind("alpha/", 0) == 0;
  }
  // Back off until the contact is gone.
  sim.set_input(0, drive_panel(-0.5f, 0.0f));
  for (int i = 0; i < 2000; ++i) {
    sim.step();
    for (auto& e : sim.take_events()) log.push_back(std::move(e));
  }
  const SimEvent* started = nullptr;
  const SimEvent* stopped = nullptr;
  for (const auto& e : log) {
    const bool between = e.a.rfind("alpha/", 0) == 0 && e.b.rfind("bravo/", 0) == 0;
    if (e.kind == SimEventKind::CollisionStarted && between && !started) started = &e;
    if (e.kind == SimEventKind::CollisionStopped && started && e.a == started->a && e.b == started->b) stopped = &e;
  }
  REQUIRE(started != nullptr);
  INFO(started->a << " hit " << started->b << " at " << started->time_s << " s: " << started->detail);
  // Alpha's front (chassis or front wheels) meets bravo's left track or chassis.
  CHECK((started->a == "alpha/chassis" || started->a == "alpha/wheel_fl" || started->a == "alpha/wheel_fr"));
  CHECK((started->b == "bravo/track_left" || started->b == "bravo/chassis" || started->b == "bravo/track_right"));
  CHECK(started->detail.rfind("impact ", 0) == 0);
  CHECK(stopped != nullptr);
  CHECK(alpha_sees_bravo);
  CHECK(bravo_sees_alpha);
  // Alpha could not drive through bravo (half its length 0.4 m + half bravo's
  // width over the tracks 0.35 m, less a few mm of contact): it pushed the
  // braked robot sideways instead.
  INFO("closest " << closest_m << " m; bravo pushed to x = " << sim.snapshot(1).position_m[0]);
  CHECK(closest_m > 0.74);
  CHECK(sim.snapshot(1).position_m[0] > 2.5 + 0.5);
}

TEST_CASE("two runs with the same seed and inputs give bit-identical trajectories for two robots", "[sim]") {
  auto trajectory = [] {
    // Bravo starts across alpha's path: they meet, so contacts between robots are in the run.
    std::vector<RobotSpec> robots{spec("alpha", "tracked_eod", 0.0, 0.0, 0.0), spec("bravo", "skid4", 2.0, -1.5, 90.0)};
    Simulation sim(robots, default_world());
    std::vector<double> out;
    for (int i = 0; i < 4000; ++i) {
      sim.set_input(0, drive_panel(i < 2000 ? 1.0f : 0.5f, i < 2000 ? 0.0f : 0.6f));
      sim.set_input(1, drive_panel(0.6f, i < 1000 ? 0.0f : -0.3f));
      sim.step();
      if (i % 100 == 0) {
        for (std::size_t r = 0; r < 2; ++r) {
          const auto s = sim.snapshot(r);
          out.insert(out.end(), {s.position_m[0], s.position_m[1], s.position_m[2], s.orientation_wxyz[3],
                                 s.odometry.position_m[0], s.imu.angular_velocity_radps[2]});
        }
      }
    }
    std::size_t between = 0;
    for (const auto& e : sim.take_events())
      between += e.kind == SimEventKind::CollisionStarted && e.b.rfind("bravo/", 0) == 0;
    out.push_back(static_cast<double>(between));
    return out;
  };
  const auto a = trajectory();
  const auto b = trajectory();
  REQUIRE(a.size() == b.size());
  CHECK(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
  CHECK(a.back() > 0);  // the robots did touch
}

TEST_CASE("robots start at the world's robot_start and robot_starts unless given a start", "[sim]") {
  const auto world = parse_world_description(
      "world: w\nrobot_start: {xy_m: [1.0, 2.0], yaw_deg: 90}\nrobot_starts:\n  - {xy_m: [-3.0, 0.5], yaw_deg: 180}\n",
      "w.yaml");
  REQUIRE(world.robot_starts.size() == 1);
  const auto skid4 = load_robot_description(kRobots + "skid4.yaml");
  {
    Simulation sim({RobotSpec{"a", skid4, std::nullopt}, RobotSpec{"b", skid4, std::nullopt}}, world);
    CHECK(sim.snapshot(0).position_m[0] == Approx(1.0).margin(1e-9));
    CHECK(sim.snapshot(0).position_m[1] == Approx(2.0).margin(1e-9));
    CHECK(sim.snapshot(1).position_m[0] == Approx(-3.0).margin(1e-9));
    CHECK(sim.snapshot(1).position_m[1] == Approx(0.5).margin(1e-9));
    CHECK(std::fabs(sim.snapshot(1).yaw_rad()) == Approx(M_PI).margin(1e-9));
  }
  // A caller's start wins over the world's.
  Simulation given({RobotSpec{"a", skid4, RobotStart{{5.0, 5.0}, 0.0}}}, world);
  CHECK(given.snapshot().position_m[0] == Approx(5.0).margin(1e-9));

  using rise::sim::testing::error_of;
  const auto make = [&](std::vector<RobotSpec> robots) {
    try {
      Simulation sim(std::move(robots), world);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK(make({RobotSpec{"a", skid4, {}}, RobotSpec{"b", skid4, {}}, RobotSpec{"c", skid4, {}}}) ==
        "simulation: robot 'c': no start pose (the world has robot_start and 1 robot_starts)");
  CHECK(make({RobotSpec{"a", skid4, {}}, RobotSpec{"a", skid4, {}}}) == "simulation: robot id 'a' twice");
  CHECK(make({RobotSpec{"a/b", skid4, {}}}) == "simulation: robot 0: bad id 'a/b' (needs one, without '/')");
  CHECK(make({}) == "simulation: no robots");
  CHECK_THAT(error_of([] { parse_world_description("robot_starts:\n  - {xy_m: [1.0]}\n", "w.yaml"); }),
             Catch::StartsWith("w.yaml:2: robot_starts[0].xy_m: expected [x, y]"));
}

TEST_CASE("a robot's rays see the other robot but never its own parts, and region events name each robot", "[sim]") {
  WorldDescription world;
  world.regions.push_back({"zone", {1.5, -1.0, 0.0}, {3.5, 1.0, 1.5}});
  std::vector<RobotSpec> robots{spec("alpha", "skid4", 0.0, 0.0, 0.0), spec("bravo", "skid4", 4.0, 0.0, 0.0)};
  Simulation sim(robots, world);
  // Along x at chassis height: alpha's own chassis is skipped, bravo's rear face is at 4 - 0.4.
  const double inf = std::numeric_limits<double>::infinity();
  const double chassis_z = sim.snapshot(0).position_m[2];
  CHECK(sim.cast_ray_m({0.0, 0.0, chassis_z}, {1, 0, 0}, 10.0, 0) == Approx(3.6).margin(1e-3));
  CHECK(sim.cast_ray_m({0.0, 0.0, chassis_z}, {1, 0, 0}, 10.0, 1) == Approx(0.4).margin(1e-3));  // alpha's front face
  CHECK(sim.cast_ray_m({4.0, 0.0, chassis_z}, {1, 0, 0}, 10.0, 1) == inf);

  sim.set_input(0, drive_panel(0.5f, 0.0f));
  sim.set_input(1, idle_panel());
  std::vector<SimEvent> entered;
  for (int i = 0; i < 5000 && entered.empty(); ++i) {
    sim.step();
    for (const auto& e : sim.take_events())
      if (e.kind == SimEventKind::RegionEntered) entered.push_back(e);
  }
  REQUIRE(entered.size() == 1);
  CHECK(entered[0].a == "alpha");
  CHECK(entered[0].b == "zone");
}
