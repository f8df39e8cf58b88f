#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "sim/laser_scanner.hpp"
#include "sim/simulation.hpp"
#include "tests/sim/sim_panel.hpp"

using namespace rise::sim;
using rise::sim::testing::drive_panel;
using rise::sim::testing::run_for;

namespace {
RobotDescription tracked() { return load_robot_description(std::string(RISE_SOURCE_DIR) + "/sim/robots/tracked_eod.yaml"); }
RobotDescription skid() { return load_robot_description(std::string(RISE_SOURCE_DIR) + "/sim/robots/skid4.yaml"); }

double wheel_speed(const RobotSnapshot& s, const std::string& name) {
  for (const auto& w : s.wheels)
    if (w.name == name) return w.velocity_radps;
  return NAN;
}
PhysicsFault fault(const std::string& id, SimFaultKind kind, const std::string& target, double value,
                   double duration_s) {
  PhysicsFault f;
  f.id = id;
  f.kind = kind;
  f.target = target;
  f.value = value;
  f.duration_s = duration_s;
  f.seed = 11;
  return f;
}
// Dead-man held, mode = arm, the shoulder stick pushing the arm down.
ControlInput shoulder_down() {
  ControlInput in = drive_panel(0.0f, 0.0f);
  in.axes = {{"arm_x", 0.0f}, {"arm_y", -1.0f}, {"arm_twist", 0.0f}};
  in.switches = {{"mode", 1}, {"speed", 2}};
  in.switch_labels = {{"mode", "arm"}, {"speed", "fast"}};
  return in;
}
// Steps for `seconds`; the name of the first joint that broke, or "" if none did.
std::string first_broken_joint(Simulation& sim, double seconds) {
  const auto steps = static_cast<int>(std::lround(seconds / Simulation::kStepS));
  for (int i = 0; i < steps; ++i) {
    sim.step();
    for (const auto& e : sim.take_events())
      if (e.kind == SimEventKind::JointBroken) return e.b;
  }
  return {};
}
bool has_event(const std::vector<SimEvent>& events, SimEventKind kind, const std::string& b) {
  for (const auto& e : events)
    if (e.kind == kind && e.b == b) return true;
  return false;
}
}  // namespace

TEST_CASE("a motor failure stops one track, turns the robot and clears after its duration", "[sim]") {
  Simulation sim(tracked(), WorldDescription{});
  sim.set_input(drive_panel(1.0f, 0.0f));
  run_for(sim, 1.0);
  const RobotSnapshot before = sim.snapshot();
  CHECK(wheel_speed(before, "track_left") == Approx(wheel_speed(before, "track_right")).margin(1e-6));
  CHECK(wheel_speed(before, "track_left") > 0.5);

  REQUIRE(sim.set_fault(0, fault("m1", SimFaultKind::MotorFailure, "left", 0.0, 2.0)).empty());
  CHECK(has_event(sim.take_events(), SimEventKind::FaultInjected, "m1"));
  const double yaw0 = sim.snapshot().yaw_rad();
  run_for(sim, 1.0);
  const RobotSnapshot during = sim.snapshot();
  CHECK(wheel_speed(during, "track_left") == 0.0);
  CHECK(wheel_speed(during, "track_right") > 0.5);
  CHECK(during.yaw_rad() - yaw0 > 0.1);  // the right track alone turns it left (counter-clockwise)
  REQUIRE(during.active_faults.size() == 1);
  CHECK(during.active_faults[0] == "m1: motor_failure left");

  run_for(sim, 1.1);
  const RobotSnapshot after = sim.snapshot();
  CHECK(has_event(sim.take_events(), SimEventKind::FaultCleared, "m1"));
  CHECK(after.active_faults.empty());
  CHECK(wheel_speed(after, "track_left") == Approx(wheel_speed(after, "track_right")).margin(1e-6));
}

TEST_CASE("motor weakness slows one side of a wheeled robot until it is cleared", "[sim]") {
  Simulation sim(skid(), WorldDescription{});
  sim.set_input(drive_panel(1.0f, 0.0f));
  REQUIRE(sim.set_fault(0, fault("weak", SimFaultKind::MotorWeakness, "right", 0.5, 0.0)).empty());
  run_for(sim, 1.0);
  const RobotSnapshot s = sim.snapshot();
  const double left = wheel_speed(s, "wheel_fl"), right = wheel_speed(s, "wheel_fr");
  CHECK(right > 0.0);
  CHECK(right < 0.75 * left);
  CHECK(sim.clear_fault(0, "weak") == 1);
  CHECK(has_event(sim.take_events(), SimEventKind::FaultCleared, "weak"));
  run_for(sim, 1.0);
  const RobotSnapshot c = sim.snapshot();
  CHECK(wheel_speed(c, "wheel_fr") == Approx(wheel_speed(c, "wheel_fl")).epsilon(0.05));
}

TEST_CASE("track slip makes the robot cover less ground", "[sim]") {
  const auto distance = [](bool slip) {
    Simulation sim(tracked(), WorldDescription{});
    if (slip) REQUIRE(sim.set_fault(0, fault("s", SimFaultKind::TrackSlip, "left", 0.05, 0.0)).empty());
    if (slip) REQUIRE(sim.set_fault(0, fault("s2", SimFaultKind::TrackSlip, "right", 0.05, 0.0)).empty());
    sim.set_input(drive_panel(1.0f, 0.0f));
    run_for(sim, 2.0);
    const auto p = sim.snapshot().position_m;
    return std::hypot(p[0], p[1]);
  };
  const double nominal = distance(false);
  const double slipping = distance(true);
  CHECK(nominal > 0.5);
  CHECK(slipping < 0.8 * nominal);
}

TEST_CASE("faults with a bad target are refused with the reason", "[sim]") {
  Simulation sim(tracked(), WorldDescription{});
  CHECK_THAT(sim.set_fault(0, fault("x", SimFaultKind::MotorFailure, "middle", 0, 0)), Catch::Contains("left or right"));
  CHECK_THAT(sim.set_fault(0, fault("x", SimFaultKind::WeakJoint, "knee", 0, 0)), Catch::Contains("no joint 'knee'"));
  CHECK_THAT(sim.set_fault(0, fault("x", SimFaultKind::CameraBlackout, "nose", 0, 0)), Catch::Contains("no camera"));
  CHECK_THAT(sim.set_fault(3, fault("x", SimFaultKind::MotorFailure, "left", 0, 0)), Catch::Contains("no robot"));
  CHECK(sim.set_fault(0, fault("w", SimFaultKind::WeakJoint, "elbow_pitch", 0.3, 0)).empty());
  CHECK(sim.faults(0).size() == 1);
}

TEST_CASE("a weak joint breaks under a push the healthy joint holds and is whole again after the fault", "[sim]") {
  // The shipped shoulder motor (120 N·m) pressing the gripper into the floor
  // cannot break its 300 N·m joint; at 0.3 of that limit (90 N·m) it can.
  Simulation healthy(tracked(), WorldDescription{});
  healthy.set_input(shoulder_down());
  CHECK(first_broken_joint(healthy, 4.0).empty());

  Simulation weakened(tracked(), WorldDescription{});
  REQUIRE(weakened.set_fault(0, fault("wj", SimFaultKind::WeakJoint, "shoulder_pitch", 0.3, 0.0)).empty());
  weakened.set_input(shoulder_down());
  CHECK(first_broken_joint(weakened, 4.0) == "shoulder_pitch");
  const RobotSnapshot s = weakened.snapshot();
  CHECK(s.damage > 0.0);
  const auto broken = std::count_if(s.joints.begin(), s.joints.end(), [](const JointState& j) { return j.broken; });
  CHECK(broken == 1);

  // The same fault lasting 0.5 s, over before the push: the joint has its
  // nominal limit back and holds the push again.
  Simulation restored(tracked(), WorldDescription{});
  REQUIRE(restored.set_fault(0, fault("wj", SimFaultKind::WeakJoint, "shoulder_pitch", 0.3, 0.5)).empty());
  CHECK(first_broken_joint(restored, 0.6).empty());
  CHECK(restored.faults(0).empty());
  CHECK(restored.snapshot().active_faults.empty());
  restored.set_input(shoulder_down());
  CHECK(first_broken_joint(restored, 4.0).empty());
}

TEST_CASE("scanner dropout removes returns and scanner noise moves them, both seeded", "[sim]") {
  const RobotDescription robot = skid();
  REQUIRE(robot.sensors.laser);
  const auto scan = [&](std::optional<PhysicsFault> f) {
    Simulation sim(robot, default_world());
    if (f) REQUIRE(sim.set_fault(0, *f).empty());
    LaserScanner scanner(*robot.sensors.laser, robot.sensors.seed);
    return scanner.scan(sim);
  };
  const LaserScan clean = scan(std::nullopt);
  REQUIRE(clean.points_sensor.size() > 50);
  CHECK(scan(fault("d", SimFaultKind::ScannerDropout, "laser", 1.0, 0)).points_sensor.empty());
  const LaserScan half = scan(fault("d", SimFaultKind::ScannerDropout, "laser", 0.5, 0));
  const auto fraction = static_cast<double>(half.points_sensor.size()) / static_cast<double>(clean.points_sensor.size());
  CHECK(fraction < 0.7);
  CHECK(fraction > 0.3);
  const LaserScan noisy = scan(fault("n", SimFaultKind::ScannerNoise, "", 0.2, 0));
  const LaserScan noisy_again = scan(fault("n", SimFaultKind::ScannerNoise, "", 0.2, 0));
  double moved = 0.0;
  int both = 0;
  for (std::size_t i = 0; i < clean.ranges_m.size(); ++i) {
    if (std::isnan(clean.ranges_m[i]) || std::isnan(noisy.ranges_m[i])) continue;
    moved += std::abs(noisy.ranges_m[i] - clean.ranges_m[i]);
    ++both;
  }
  REQUIRE(both > 20);
  CHECK(moved / static_cast<double>(both) > 0.08);  // mean |N(0, 0.2)| = 0.16
  CHECK(noisy.ranges_m.size() == noisy_again.ranges_m.size());
  for (std::size_t i = 0; i < noisy.ranges_m.size(); ++i)
    if (!std::isnan(noisy.ranges_m[i])) CHECK(noisy.ranges_m[i] == noisy_again.ranges_m[i]);
}

TEST_CASE("a camera blackout covers the named camera until it ends", "[sim]") {
  const RobotDescription robot = tracked();
  REQUIRE_FALSE(robot.sensors.cameras.empty());
  const std::string camera = robot.sensors.cameras.front().name;
  Simulation sim(robot, WorldDescription{});
  CHECK_FALSE(sim.camera_blacked_out(camera));
  REQUIRE(sim.set_fault(0, fault("b", SimFaultKind::CameraBlackout, camera, 0, 0.5)).empty());
  CHECK(sim.camera_blacked_out(camera));
  run_for(sim, 0.6);
  CHECK_FALSE(sim.camera_blacked_out(camera));
}
