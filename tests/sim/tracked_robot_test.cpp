#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "sim/simulation.hpp"

using namespace rise::sim;

namespace {
const std::string kTracked = std::string(RISE_SOURCE_DIR) + "/sim/robots/tracked_eod.yaml";
const std::string kBuilding = std::string(RISE_SOURCE_DIR) + "/sim/worlds/building.yaml";

RobotDescription tracked() { return load_robot_description(kTracked); }
WorldDescription building() { return load_world_description(kBuilding); }

// A panel with the dead-man held, the given mode and speed switch positions and sticks.
ControlInput panel(const std::string& mode, int speed = 2) {
  static const char* const kSpeeds[] = {"slow", "medium", "fast"};
  ControlInput in;
  in.fresh = true;
  in.failsafe = false;
  in.deadman = true;
  in.buttons = {{"estop", false}, {"gripper_open", false}, {"gripper_close", false}};
  in.switches = {{"mode", mode == "arm" ? 1 : 0}, {"speed", speed}};
  in.switch_labels = {{"mode", mode}, {"speed", kSpeeds[speed]}};
  return in;
}

ControlInput drive(float forward, float turn_right, int speed = 2) {
  ControlInput in = panel("drive", speed);
  in.axes = {{"drive_y", forward}, {"drive_x", turn_right}};
  return in;
}

ControlInput arm(float x, float y, float twist) {
  ControlInput in = panel("arm");
  in.axes = {{"arm_x", x}, {"arm_y", y}, {"arm_twist", twist}};
  return in;
}

void run(Simulation& sim, double seconds) {
  const auto steps = static_cast<int>(std::lround(seconds / Simulation::kStepS));
  for (int i = 0; i < steps; ++i) sim.step();
}

double yaw_deg(const RobotSnapshot& s) { return s.yaw_rad() * 180.0 / M_PI; }

// Steps until an event of `kind` (optionally naming `b`) or `seconds` of sim
// time; returns the event's time or -1. Every event seen lands in `log`.
double run_until(Simulation& sim, SimEventKind kind, double seconds, std::vector<SimEvent>& log,
                 const std::string& b = "") {
  const auto steps = static_cast<int>(std::lround(seconds / Simulation::kStepS));
  for (int i = 0; i < steps; ++i) {
    sim.step();
    for (auto& e : sim.take_events()) {
      log.push_back(e);
      if (e.kind == kind && (b.empty() || e.b == b)) return e.time_s;
    }
  }
  return -1.0;
}

bool any(const std::vector<SimEvent>& log, SimEventKind kind) {
  return std::any_of(log.begin(), log.end(), [&](const SimEvent& e) { return e.kind == kind; });
}
}  // namespace

TEST_CASE("the tracked robot file loads with tracks and an arm mapped to the panel", "[sim]") {
  const auto r = tracked();
  CHECK(r.kind == RobotKind::Tracked);
  CHECK(r.tracks.max_speed_mps == Approx(1.0).margin(1e-9));
  CHECK(r.tracks.approach_rad == Approx(40.0 * M_PI / 180.0).margin(1e-9));
  REQUIRE(r.arm.has_value());
  REQUIRE(r.control.arm.has_value());
  REQUIRE(r.control.arm->joints.size() == 3);
  CHECK(r.control.arm->joints[0].joint == "shoulder_yaw");
  CHECK(r.control.arm->joints[1].axis.axis == "arm_y");
  CHECK(r.control.arm->joints[2].break_torque_nm == Approx(150.0).margin(1e-9));
  CHECK(r.control.arm->open_button == "gripper_open");
  CHECK(load_robot_description(std::string(RISE_SOURCE_DIR) + "/sim/robots/skid4.yaml").kind == RobotKind::SkidSteer);
}

TEST_CASE("a broken tracked robot file is refused with file:line and the key", "[sim]") {
  const std::string good = "robot: t\nkind: tracked\nchassis: {mass_kg: 50}\ntracks: {radius_m: 0.09}\n"
                           "arm: {upper_length_m: 0.4}\ncontrol:\n  linear: {axis: drive_y, max_mps: 1}\n"
                           "  angular: {axis: drive_x, max_radps: 1}\n  arm:\n"
                           "    shoulder_yaw: {axis: arm_x, max_radps: 1}\n"
                           "    shoulder_pitch: {axis: arm_y, max_radps: 1}\n"
                           "    elbow_pitch: {axis: arm_twist, max_radps: 1, min_deg: -90, max_deg: 90}\n"
                           "    gripper: {open: gripper_open, close: gripper_close}\n";
  CHECK_NOTHROW(parse_robot_description(good, "t.yaml"));
  struct Case {
    const char* find;
    const char* replace;
    const char* expected;
  };
  const auto c = GENERATE(Case{"kind: tracked", "kind: legged", "t.yaml:2: kind: expected skid_steer, tracked or urdf_tree"},
                          Case{"radius_m: 0.09", "radius_m: 0", "t.yaml:4: tracks.radius_m: must be > 0"},
                          Case{"min_deg: -90", "min_deg: 10", "t.yaml:12: control.arm.elbow_pitch.min_deg: limits"},
                          Case{"    shoulder_pitch: {axis: arm_y, max_radps: 1}\n", "",
                               "t.yaml:10: control.arm.shoulder_pitch: missing"},
                          Case{"open: gripper_open, ", "", "t.yaml:13: control.arm.gripper: needs open and close"},
                          Case{"tracks: {radius_m: 0.09}", "wheels: {radius_m: 0.09}",
                               "t.yaml:4: wheels: a tracked robot has tracks"});
  std::string text = good;
  const auto at = text.find(c.find);
  REQUIRE(at != std::string::npos);
  text.replace(at, std::string(c.find).size(), c.replace);
  std::string error = "no error";
  try {
    parse_robot_description(text, "t.yaml");
  } catch (const std::runtime_error& e) {
    error = e.what();
  }
  INFO(error);
  CHECK(error.rfind(c.expected, 0) == 0);
}

TEST_CASE("the tracked robot drives straight at its commanded speed", "[sim]") {
  Simulation sim(tracked(), WorldDescription{});
  sim.set_input(drive(1.0f, 0.0f));
  run(sim, 5.0);
  const auto s = sim.snapshot();
  // Tolerances: 5 cm lateral drift and 2° heading over ~4 m; speed within 5 % of 0.8 m/s.
  CHECK(std::fabs(s.position_m[1]) < 0.05);
  CHECK(std::fabs(yaw_deg(s)) < 2.0);
  CHECK(s.speed_mps() == Approx(0.8).epsilon(0.05));
  CHECK(s.position_m[0] > 3.7);
  REQUIRE(s.wheels.size() == 2);
  CHECK(s.wheels[0].name == "track_left");
  CHECK(s.wheels[0].velocity_radps == Approx(0.8 / 0.09).epsilon(0.01));
}

TEST_CASE("the tracked robot turns in place", "[sim]") {
  Simulation sim(tracked(), WorldDescription{});
  sim.set_input(drive(0.0f, -0.5f));  // stick left → turn left (counter-clockwise), 0.6 rad/s
  run(sim, 3.0);
  const auto s = sim.snapshot();
  INFO("yaw after 3 s: " << yaw_deg(s) << "°, rate " << s.angular_velocity_radps[2] << " rad/s");
  // Tolerances: the base stays within 5 cm of its start; the rate is 80..110 % of 0.6 rad/s.
  CHECK(std::hypot(s.position_m[0], s.position_m[1]) < 0.05);
  CHECK(s.angular_velocity_radps[2] > 0.8 * 0.6);
  CHECK(s.angular_velocity_radps[2] < 1.1 * 0.6);
  CHECK(yaw_deg(s) > 80.0);
}

TEST_CASE("the tracked robot brakes to standstill when motion is not allowed", "[sim]") {
  const double stop = stop_time_s(tracked(), 0.8);
  // Stated bound: from 0.8 m/s to standstill within 0.5 s of simulated time.
  CHECK(stop > 0.0);
  CHECK(stop < 0.5);
}

TEST_CASE("the tracked robot climbs the shipped staircase to the landing", "[sim]") {
  struct Case {
    int speed;       // speed switch position
    double bound_s;  // stated bound on the sim time to the landing
  };
  // Fast (0.8 m/s): 1.5 m approach + 6 steps, measured ~4.6 s, bound 8 s.
  // Slow (0.24 m/s): measured ~14.7 s, bound 20 s.
  const auto c = GENERATE(Case{2, 8.0}, Case{0, 20.0});
  auto world = building();
  world.robot_start_m = {-1.0, 4.25};  // in the corridor, 1.5 m before the first riser, facing it
  Simulation sim(tracked(), world);
  sim.set_input(drive(1.0f, 0.0f, c.speed));
  std::vector<SimEvent> log;
  const double t = run_until(sim, SimEventKind::StairsClimbed, c.bound_s + 2.0, log, "staircase");
  INFO("speed " << c.speed << ": stairs climbed after " << t << " s");
  CHECK(t > 0.0);
  CHECK(t < c.bound_s);
  const auto s = sim.snapshot();
  CHECK(s.position_m[2] > world.stairs[0].landing_height_m());
  CHECK_FALSE(any(log, SimEventKind::TippedOver));
  CHECK_FALSE(any(log, SimEventKind::JointBroken));
  CHECK(any(log, SimEventKind::CollisionStarted));  // the tracks met the staircase
}

TEST_CASE("pushing the door slowly opens it without breaking the hinge", "[sim]") {
  Simulation sim(tracked(), building());
  sim.set_input(drive(1.0f, 0.0f, 0));  // speed slow: 0.24 m/s toward the door 3 m ahead
  std::vector<SimEvent> log;
  const double t = run_until(sim, SimEventKind::DoorOpened, 20.0, log);
  REQUIRE(t > 0.0);
  CHECK(log.back().a == "door_ab");
  run(sim, 3.0);
  for (auto& e : sim.take_events()) log.push_back(e);
  CHECK(std::fabs(sim.door_angle_rad("door_ab")) > 10.0 * M_PI / 180.0);
  CHECK_FALSE(any(log, SimEventKind::JointBroken));
  CHECK(std::isnan(sim.door_angle_rad("no_such_door")));
}

TEST_CASE("ramming the door at full speed breaks its hinge", "[sim]") {
  Simulation sim(tracked(), building());
  sim.set_input(drive(1.0f, 0.0f));  // 0.8 m/s
  std::vector<SimEvent> log;
  const double t = run_until(sim, SimEventKind::JointBroken, 8.0, log);
  REQUIRE(t > 0.0);
  CHECK(log.back().a == "door_ab");
  CHECK(log.back().b == "hinge");
  CHECK(sim.snapshot().damage == 0.0);  // the door broke, not the robot
  run(sim, 3.0);  // off its hinge, the panel falls onto the floor, not through it
  const auto door = sim.object_position_m("door_ab");
  CHECK(door[2] > -0.05);
  CHECK(door[2] < 1.1);
}

TEST_CASE("the panel's arm axes move the arm joints in mode arm only", "[sim]") {
  const auto mapping = tracked().control;
  auto c = map_arm_controls(mapping, drive(0.0f, 0.0f));
  CHECK_FALSE(c.enabled);
  CHECK(c.stop_reason == "mode not arm");
  c = map_arm_controls(mapping, arm(1.0f, 0.5f, -1.0f));
  REQUIRE(c.enabled);
  REQUIRE(c.joint_radps.size() == 3);
  CHECK(c.joint_radps[0] == Approx(-0.8).margin(1e-9));  // stick right → clockwise
  CHECK(c.joint_radps[1] == Approx(0.3).margin(1e-9));
  CHECK(c.joint_radps[2] == Approx(-0.8).margin(1e-9));

  Simulation sim(tracked(), WorldDescription{});
  const auto start = sim.snapshot().gripper_position_m;
  sim.set_input(arm(0.0f, 1.0f, 0.0f));  // shoulder up
  run(sim, 1.0);
  auto s = sim.snapshot();
  REQUIRE(s.joints.size() == 4);
  CHECK(s.joints[1].position > 0.3);
  CHECK(s.gripper_position_m[2] > start[2] + 0.1);
  CHECK(s.arm_enabled);
  CHECK_FALSE(s.motors_enabled);  // the tracks do not move in mode arm
  auto in = arm(1.0f, 0.0f, 0.0f);  // turret clockwise: the gripper swings to the right (−y)
  sim.set_input(in);
  run(sim, 1.0);
  s = sim.snapshot();
  CHECK(s.joints[0].position < -0.5);
  CHECK(s.gripper_position_m[1] < start[1] - 0.1);
  in = arm(0.0f, 0.0f, 0.0f);
  in.buttons["gripper_close"] = true;
  sim.set_input(in);
  run(sim, 1.0);
  CHECK(sim.snapshot().joints[3].position < -0.03);
  CHECK(sim.snapshot().damage == 0.0);
}

TEST_CASE("pushing the gripper into the floor harder than the shoulder can take breaks it", "[sim]") {
  // The shipped shoulder motor (120 N·m) cannot break its 300 N·m joint; a
  // motor upgraded to 450 N·m pressing the gripper into the floor can.
  auto robot = tracked();
  robot.control.arm->joints[1].max_torque_nm = 450.0;
  Simulation sim(robot, WorldDescription{});
  sim.set_input(arm(0.0f, -1.0f, 0.0f));  // shoulder down, into the floor
  std::vector<SimEvent> log;
  const double t = run_until(sim, SimEventKind::JointBroken, 8.0, log);
  REQUIRE(t > 0.0);
  CHECK(log.back().a == "tracked_eod");
  INFO(log.back().b << ": " << log.back().detail);
  const auto s = sim.snapshot();
  CHECK(s.damage > 0.0);
  const auto broken = std::count_if(s.joints.begin(), s.joints.end(), [](const JointState& j) { return j.broken; });
  CHECK(broken == 1);
  run(sim, 1.0);  // the loose link falls; the simulation carries on
  CHECK(std::isfinite(sim.snapshot().position_m[2]));

  Simulation shipped(tracked(), WorldDescription{});
  shipped.set_input(arm(0.0f, -1.0f, 0.0f));
  log.clear();
  CHECK(run_until(shipped, SimEventKind::JointBroken, 4.0, log) < 0.0);
}

TEST_CASE("driving into a region emits entered and left events", "[sim]") {
  WorldDescription world;
  world.regions.push_back({"zone", {1.0, -1.0, 0.0}, {2.0, 1.0, 1.0}});
  Simulation sim(tracked(), world);
  sim.set_input(drive(1.0f, 0.0f));
  std::vector<SimEvent> log;
  const double entered = run_until(sim, SimEventKind::RegionEntered, 5.0, log, "zone");
  REQUIRE(entered > 0.0);
  CHECK(log.back().a == "tracked_eod");
  CHECK(sim.snapshot().position_m[0] >= 1.0);
  const double left = run_until(sim, SimEventKind::RegionLeft, 5.0, log, "zone");
  CHECK(left > entered);
  CHECK(sim.snapshot().position_m[0] > 2.0);
}

TEST_CASE("pushing a movable object emits object moved", "[sim]") {
  WorldDescription world;
  world.objects.push_back({"crate", {0.3, 0.6, 0.3}, 3.0, {1.5, 0.0, 0.15}});
  Simulation sim(tracked(), world);
  sim.set_input(drive(0.5f, 0.0f));
  std::vector<SimEvent> log;
  const double t = run_until(sim, SimEventKind::ObjectMoved, 8.0, log);
  REQUIRE(t > 0.0);
  CHECK(log.back().a == "crate");
  CHECK(any(log, SimEventKind::CollisionStarted));
  CHECK(sim.object_position_m("crate")[0] > 1.5);
}

TEST_CASE("driving off the landing tips the tracked robot over", "[sim]") {
  auto world = building();
  world.robot_start_m = {-1.0, 4.25};
  Simulation sim(tracked(), world);
  sim.set_input(drive(1.0f, 0.0f, 1));  // medium, 0.48 m/s
  std::vector<SimEvent> log;
  // Up the stairs and straight off the far edge of the 1 m high landing, nose first.
  const double t = run_until(sim, SimEventKind::TippedOver, 14.0, log);
  CHECK(t > 0.0);
  CHECK(any(log, SimEventKind::StairsClimbed));
}

TEST_CASE("two runs with the same inputs give bit-identical trajectories in the building", "[sim]") {
  auto trajectory = [] {
    Simulation sim(tracked(), building());
    std::vector<double> out;
    for (int i = 0; i < 6000; ++i) {
      if (i < 1000) sim.set_input(arm(0.5f, 0.7f, -0.5f));
      else if (i < 4000) sim.set_input(drive(1.0f, 0.05f));
      else sim.set_input(drive(0.5f, 0.6f));
      sim.step();
      if (i % 100 == 0) {
        const auto s = sim.snapshot();
        out.insert(out.end(), {s.position_m[0], s.position_m[1], s.position_m[2], s.orientation_wxyz[3],
                               s.gripper_position_m[0], s.gripper_position_m[2], sim.door_angle_rad("door_ab")});
      }
    }
    out.push_back(static_cast<double>(sim.take_events().size()));
    return out;
  };
  const auto a = trajectory();
  const auto b = trajectory();
  REQUIRE(a.size() == b.size());
  CHECK(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

TEST_CASE("the skid-steer robot also runs in the building world", "[sim]") {
  Simulation sim(load_robot_description(std::string(RISE_SOURCE_DIR) + "/sim/robots/skid4.yaml"), building());
  sim.set_input(drive(0.5f, 0.0f));
  run(sim, 3.0);
  const auto s = sim.snapshot();
  CHECK(s.position_m[0] > 1.0);
  CHECK(s.joints.empty());
  CHECK(std::string(to_string(SimEventKind::StairsClimbed)) == "stairs_climbed");
}
