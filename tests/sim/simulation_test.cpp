#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include "sim/simulation.hpp"
#include "tests/sim/sim_panel.hpp"

using namespace rise::sim;

namespace {
const std::string kRobot = std::string(RISE_SOURCE_DIR) + "/sim/robots/skid4.yaml";

RobotDescription robot() { return load_robot_description(kRobot); }

// A panel with the dead-man held, mode=drive, speed=fast and the given sticks.
constexpr auto drive = &rise::sim::testing::drive_panel;
constexpr auto run = &rise::sim::testing::run_for;

double yaw_deg(const RobotSnapshot& s) { return s.yaw_rad() * 180.0 / M_PI; }

std::string load_error(const std::string& text) {
  try {
    parse_robot_description(text, "bad.yaml");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}
}  // namespace

TEST_CASE("the shipped robot file loads", "[sim]") {
  const auto r = robot();
  CHECK(r.name == "skid4");
  CHECK(r.chassis.mass_kg == Approx(40.0));
  CHECK(r.wheels.radius_m == Approx(0.12));
  CHECK(r.control.linear.axis == "drive_y");
  CHECK(r.control.angular.invert);
  REQUIRE(r.control.speed_scale.has_value());
  CHECK(r.control.speed_scale->second.size() == 3);
  CHECK(r.control.estop_button == std::optional<std::string>("estop"));
}

TEST_CASE("a broken robot file is refused with file:line and the key", "[sim]") {
  std::ifstream in(std::string(RISE_SOURCE_DIR) + "/tests/sim/data/skid4_inline.yaml");  // the inline form
  std::stringstream buf;
  buf << in.rdbuf();
  const std::string good = buf.str();
  struct Case {
    const char* find;
    const char* replace;
    const char* expected;
  };
  const auto c = GENERATE(Case{"radius_m: 0.12", "radius_m: -0.12", "bad.yaml:9: wheels.radius_m: must be > 0"},
                          Case{"radius_m: 0.12", "radius: 0.12", "bad.yaml:9: wheels.radius: unknown key"},
                          Case{"mass_kg: 40", "mass_kg: heavy", "bad.yaml:6: chassis.mass_kg: cannot read 'heavy'"},
                          Case{"linear:  {axis: drive_y, max_mps: 1.2}", "linear:  {max_mps: 1.2}",
                               "bad.yaml:19: control.linear.axis: missing"},
                          Case{"values: [0.3, 0.6, 1.0]", "values: [0.3, 0.6, 1.5]",
                               "bad.yaml:22: control.speed_scale.values: must be in 0..1"});
  std::string text = good;
  const auto at = text.find(c.find);
  REQUIRE(at != std::string::npos);
  text.replace(at, std::string(c.find).size(), c.replace);
  const auto error = load_error(text);
  INFO(error);
  CHECK(error.rfind(c.expected, 0) == 0);
  CHECK_THROWS_WITH(load_robot_description("/nonexistent/robot.yaml"), Catch::Contains("/nonexistent/robot.yaml: cannot open: No such file or directory"));
}

TEST_CASE("the shipped yard world file is the built-in default", "[sim]") {
  const auto file = load_world_description(std::string(RISE_SOURCE_DIR) + "/sim/worlds/yard.yaml");
  const auto builtin = default_world();
  REQUIRE(file.boxes.size() == builtin.boxes.size());
  for (std::size_t i = 0; i < file.boxes.size(); ++i) {
    CHECK(file.boxes[i].name == builtin.boxes[i].name);
    for (std::size_t k = 0; k < 3; ++k) {
      CHECK(file.boxes[i].center_m[k] == Approx(builtin.boxes[i].center_m[k]));
      CHECK(file.boxes[i].size_m[k] == Approx(builtin.boxes[i].size_m[k]));
    }
    CHECK(file.boxes[i].yaw_rad == Approx(builtin.boxes[i].yaw_rad).margin(0.01));
  }
  CHECK_THROWS_WITH(parse_world_description("boxes:\n  - {name: a, center_m: [0, 0], size_m: [1, 1, 1]}\n", "w.yaml"),
                    Catch::StartsWith("w.yaml:2: boxes[0].center_m: expected [x, y, z]"));
}

TEST_CASE("the robot drives straight at its commanded speed", "[sim]") {
  Simulation sim(robot(), WorldDescription{});
  sim.set_input(drive(1.0f, 0.0f));
  run(sim, 5.0);
  const auto s = sim.snapshot();
  // Tolerances: 5 cm lateral drift and 2° heading over ~5 m; speed within 10 % of 1.2 m/s.
  CHECK(std::fabs(s.position_m[1]) < 0.05);
  CHECK(std::fabs(yaw_deg(s)) < 2.0);
  CHECK(s.speed_mps() == Approx(1.2).epsilon(0.10));
  CHECK(s.position_m[0] > 4.5);
  CHECK(s.motors_enabled);
  CHECK(s.wheels.size() == 4);
}

TEST_CASE("the robot turns in place", "[sim]") {
  Simulation sim(robot(), WorldDescription{});
  sim.set_input(drive(0.0f, -0.5f));  // stick left → turn left (counter-clockwise)
  run(sim, 3.0);
  const auto s = sim.snapshot();
  CHECK(std::hypot(s.position_m[0], s.position_m[1]) < 0.10);
  // Commanded 0.75 rad/s; skid steering slips, so accept 40..110 % of w·t (net of the spin-up).
  const double turned = std::fabs(s.yaw_rad() - 0.0);
  INFO("yaw after 3 s: " << yaw_deg(s) << "°, rate " << s.angular_velocity_radps[2] << " rad/s");
  CHECK(s.angular_velocity_radps[2] > 0.4 * 0.75);
  CHECK(s.angular_velocity_radps[2] < 1.1 * 0.75);
  CHECK(turned > 0.3);
}

TEST_CASE("the robot brakes to standstill whenever motion is not allowed", "[sim]") {
  const std::string why = GENERATE(std::string("failsafe"), std::string("deadman"), std::string("estop"),
                                   std::string("stale"), std::string("mode"));
  Simulation sim(robot(), WorldDescription{});
  sim.set_input(drive(1.0f, 0.0f));
  run(sim, 3.0);
  REQUIRE(sim.snapshot().speed_mps() > 1.0);
  ControlInput in = drive(1.0f, 0.0f);
  if (why == "failsafe") in.failsafe = true;
  if (why == "deadman") in.deadman = false;
  if (why == "estop") in.buttons["estop"] = true;
  if (why == "stale") in.fresh = false;
  if (why == "mode") in.switch_labels["mode"] = "arm";
  sim.set_input(in);
  const double t0 = sim.time_s();
  double stopped_after = -1;
  for (int i = 0; i < 2000 && stopped_after < 0; ++i) {
    sim.step();
    if (sim.snapshot().speed_mps() < 0.01) stopped_after = sim.time_s() - t0;
  }
  INFO(why << ": stopped after " << stopped_after << " s");
  // Stated bound: from 1.2 m/s to standstill within 0.5 s of simulated time.
  CHECK(stopped_after > 0.0);
  CHECK(stopped_after < 0.5);
  CHECK_FALSE(sim.snapshot().motors_enabled);
  CHECK_FALSE(sim.snapshot().stop_reason.empty());
}

TEST_CASE("stop_time_s measures the robot's own braking time", "[sim]") {
  const double full = stop_time_s(robot(), 1.2);
  const double slow = stop_time_s(robot(), 0.3);
  CHECK(full > 0.0);
  CHECK(full < 0.5);
  CHECK(slow <= full);
}

TEST_CASE("two runs with the same inputs give bit-identical trajectories", "[sim]") {
  auto trajectory = [] {
    Simulation sim(robot(), default_world());
    std::vector<double> out;
    for (int i = 0; i < 3000; ++i) {
      sim.set_input(drive(i < 1500 ? 1.0f : 0.4f, i < 1500 ? 0.0f : 0.7f));
      sim.step();
      if (i % 100 == 0) {
        const auto s = sim.snapshot();
        out.insert(out.end(), {s.position_m[0], s.position_m[1], s.position_m[2], s.orientation_wxyz[3]});
      }
    }
    return out;
  };
  const auto a = trajectory();
  const auto b = trajectory();
  REQUIRE(a.size() == b.size());
  CHECK(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

TEST_CASE("driving into a box reports the box among the contacts", "[sim]") {
  WorldDescription world;
  world.boxes.push_back({"crate", {2.0, 0.0, 0.3}, {0.6, 1.0, 0.6}, 0.0});
  Simulation sim(robot(), world);
  sim.set_input(drive(0.5f, 0.0f));
  bool touched = false;
  for (int i = 0; i < 8000 && !touched; ++i) {
    sim.step();
    for (const auto& c : sim.snapshot().contacts) touched = touched || c == "crate";
  }
  CHECK(touched);
  CHECK(sim.snapshot().position_m[0] < 2.0);  // it did not drive through
}

TEST_CASE("pushing against a box reports the collision started, continuing each second, and stopped", "[sim]") {
  WorldDescription world;
  world.boxes.push_back({"crate", {2.0, 0.0, 0.3}, {0.6, 1.0, 0.6}, 0.0});
  Simulation sim(robot(), world);
  sim.set_input(drive(0.5f, 0.0f));
  std::vector<SimEvent> log;
  const auto about_crate = [&](SimEventKind kind) {
    std::vector<SimEvent> found;
    for (const auto& e : log)
      if (e.kind == kind && e.b == "crate") found.push_back(e);
    return found;
  };
  // Drive into it, keep pushing for 3.5 s after the first contact, back off.
  double started_s = -1;
  for (int i = 0; i < 20000 && (started_s < 0 || sim.time_s() < started_s + 3.5); ++i) {
    sim.step();
    for (auto& e : sim.take_events()) log.push_back(std::move(e));
    const auto s = about_crate(SimEventKind::CollisionStarted);
    if (started_s < 0 && !s.empty()) started_s = s.front().time_s;
  }
  REQUIRE(started_s >= 0);
  sim.set_input(drive(-0.5f, 0.0f));
  for (int i = 0; i < 2000; ++i) {
    sim.step();
    for (auto& e : sim.take_events()) log.push_back(std::move(e));
  }
  // One part of the robot (the first that touched) kept touching throughout.
  const auto first = about_crate(SimEventKind::CollisionStarted).front();
  std::vector<SimEvent> continues;
  for (const auto& e : about_crate(SimEventKind::CollisionContinues))
    if (e.a == first.a) continues.push_back(e);
  REQUIRE(continues.size() >= 3);
  for (std::size_t k = 0; k < 3; ++k) {
    INFO("continues " << k);
    CHECK(continues[k].time_s == Approx(first.time_s + static_cast<double>(k + 1)).margin(1e-9));
    CHECK(continues[k].detail == std::to_string(k + 1) + " s");
  }
  bool stopped = false;
  for (const auto& e : about_crate(SimEventKind::CollisionStopped)) stopped = stopped || e.a == first.a;
  CHECK(stopped);
  CHECK(std::string(to_string(SimEventKind::CollisionContinues)) == "collision_continues");
}

TEST_CASE("the control mapping scales by the speed switch and refuses an unknown position", "[sim]") {
  const auto mapping = robot().control;
  auto in = drive(1.0f, 0.0f);
  in.switches["speed"] = 0;
  auto c = map_controls(mapping, in);
  CHECK(c.enabled);
  CHECK(c.linear_mps == Approx(0.3 * 1.2));
  in.switches["speed"] = 7;
  c = map_controls(mapping, in);
  CHECK_FALSE(c.enabled);
  CHECK(c.stop_reason == "speed position unknown");
  in = drive(0.0f, 1.0f);  // stick right
  c = map_controls(mapping, in);
  CHECK(c.angular_radps == Approx(-1.5));  // clockwise
}

namespace {
// A wall across the x axis at x = 2 (0.2 m thick, faces at x = 1.9 and 2.1),
// y -2..2, with a 1.2 m wide, 2 m high opening at y -0.6..0.6 under a lintel
// up to 2.5 m.
WorldDescription wall_with_opening() {
  WorldDescription world;
  Wall wall;
  wall.name = "w";
  wall.from_m = {2.0, -2.0};
  wall.to_m = {2.0, 2.0};
  wall.height_m = 2.5;
  wall.thickness_m = 0.2;
  wall.openings.push_back({1.4, 1.2, 2.0});
  world.walls.push_back(wall);
  return world;
}
}  // namespace

TEST_CASE("a ray passes through a wall's opening and hits the pieces beside it and the lintel above", "[sim]") {
  Simulation sim(robot(), wall_with_opening());
  const Eigen::Vector3d east(1, 0, 0);
  const double inf = std::numeric_limits<double>::infinity();
  CHECK(sim.cast_ray_m({0.0, 0.0, 1.0}, east, 10.0) == inf);   // through the opening
  CHECK(sim.cast_ray_m({0.0, 0.55, 1.9}, east, 10.0) == inf);  // just inside its corner
  CHECK(sim.cast_ray_m({0.0, 0.0, 2.2}, east, 10.0) == Approx(1.9).margin(1e-6));   // the lintel
  CHECK(sim.cast_ray_m({0.0, -0.7, 1.0}, east, 10.0) == Approx(1.9).margin(1e-6));  // the piece on the right
  CHECK(sim.cast_ray_m({0.0, 0.7, 1.0}, east, 10.0) == Approx(1.9).margin(1e-6));   // the piece on the left
  CHECK(sim.cast_ray_m({0.0, 1.9, 2.4}, east, 10.0) == Approx(1.9).margin(1e-6));   // full height to the end
  // Up from the opening's floor: the lintel's underside at 2 m.
  CHECK(sim.cast_ray_m({2.0, 0.0, 0.5}, {0, 0, 1}, 10.0) == Approx(1.5).margin(1e-6));
}

TEST_CASE("the robot drives through a wall's opening without touching the wall", "[sim]") {
  Simulation sim(robot(), wall_with_opening());
  sim.set_input(drive(0.5f, 0.0f));
  bool touched = false;
  for (int i = 0; i < 15000 && sim.snapshot().position_m[0] < 3.5; ++i) {
    sim.step();
    for (const auto& c : sim.snapshot().contacts) touched = touched || c == "w";
  }
  CHECK(sim.snapshot().position_m[0] > 3.5);
  CHECK_FALSE(touched);
  for (const auto& e : sim.take_events()) CHECK(e.b != "w");
}

TEST_CASE("an upward ray hits the ceiling's underside at its height, only over its bounds", "[sim]") {
  WorldDescription world;
  world.ceiling = Ceiling{2.6, 0.1, {-5.0, -5.0}, {5.0, 5.0}};
  Simulation sim(robot(), world);
  const Eigen::Vector3d up(0, 0, 1);
  CHECK(sim.cast_ray_m({1.0, -2.0, 0.5}, up, 10.0) == Approx(2.1).margin(1e-6));
  CHECK(sim.cast_ray_m({4.9, 4.9, 0.1}, up, 10.0) == Approx(2.5).margin(1e-6));  // near its corner
  CHECK(sim.cast_ray_m({5.1, 0.0, 0.5}, up, 10.0) == std::numeric_limits<double>::infinity());
  CHECK(sim.cast_ray_m({1.0, 1.0, 3.0}, {0, 0, -1}, 10.0) == Approx(0.3).margin(1e-6));  // its top at 2.7 m
}

TEST_CASE("driving into a prop reports it by name in the contacts and the collision event", "[sim]") {
  WorldDescription world;
  world.props.push_back({{"shelf", {2.0, 0.0, 0.9}, {0.4, 1.2, 1.8}, 0.0}, "shelf"});
  Simulation sim(robot(), world);
  sim.set_input(drive(0.5f, 0.0f));
  bool touched = false, started = false;
  for (int i = 0; i < 8000 && !(touched && started); ++i) {
    sim.step();
    for (const auto& c : sim.snapshot().contacts) touched = touched || c == "shelf";
    for (const auto& e : sim.take_events())
      started = started || (e.kind == SimEventKind::CollisionStarted && e.b == "shelf");
  }
  CHECK(touched);
  CHECK(started);
  CHECK(sim.snapshot().position_m[0] < 2.0);  // it did not drive through
}
