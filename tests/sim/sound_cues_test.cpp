// The robot file's sound cues: continuous ones follow the robot, one-shots
// come once per event; a bad `sounds` section is refused with file:line.

#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <sstream>

#include "sim/simulation.hpp"
#include "tests/sim/sim_panel.hpp"

using namespace rise::sim;
using rise::sim::testing::drive_panel;
using rise::sim::testing::error_of;
using rise::sim::testing::run_for;

namespace {
const std::string kRobots = std::string(RISE_SOURCE_DIR) + "/sim/robots/";

const SoundCue& cue_named(const RobotSnapshot& s, const std::string& name) {
  for (const auto& c : s.sounds)
    if (c.name == name) return c;
  throw std::runtime_error("no sound cue " + name);
}

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream buf;
  buf << in.rdbuf();
  return buf.str();
}

struct Impact {
  double impact_mps = 0.0;  // from the collision_started event's detail
  double gain = 0.0;
  int cues = 0;             // impact cues in the run
  int events = 0;           // collision_started events of the robot at or above min_impact_mps
};

// skid4 driven at `forward` (stick, speed fast: 1.2 m/s full) into a crate 2 m ahead.
Impact drive_into_crate(float forward) {
  WorldDescription world;
  world.boxes.push_back({"crate", {2.5, 0.0, 0.3}, {0.6, 1.2, 0.6}, 0.0});
  Simulation sim(load_robot_description(kRobots + "skid4.yaml"), world);
  sim.set_input(drive_panel(forward, 0.0f));
  Impact out;
  bool first = true;
  for (int i = 0; i < 8000; ++i) {
    sim.step();
    for (const auto& e : sim.take_events()) {
      if (e.kind != SimEventKind::CollisionStarted) continue;
      const double v = std::stod(e.detail.substr(std::string("impact ").size()));
      if (v >= 0.05) ++out.events;
      if (first && e.b == "crate") {
        out.impact_mps = v;
        first = false;
      }
    }
    for (const auto& c : sim.take_sound_cues()) {
      if (c.name != "impact") continue;
      if (out.cues++ == 0) out.gain = c.gain;
      CHECK(c.robot == "skid4");
      CHECK(c.sample == "plastic_impact");
      CHECK_FALSE(c.continuous);
    }
  }
  return out;
}
}  // namespace

TEST_CASE("the engine hum is silent at rest and its gain and pitch rise with speed", "[sim]") {
  const std::string robot = GENERATE(std::string("tracked_eod"), std::string("skid4"));
  const std::string hum = robot == "skid4" ? "wheel_motors" : "tracks_motor";
  Simulation sim(load_robot_description(kRobots + robot + ".yaml"), WorldDescription{});
  ControlInput rest = drive_panel(0.0f, 0.0f);
  sim.set_input(rest);
  run_for(sim, 0.5);
  const SoundCue at_rest = cue_named(sim.snapshot(), hum);
  CHECK(at_rest.continuous);
  CHECK(at_rest.robot == robot);
  CHECK(at_rest.gain == 0.0);

  std::vector<SoundCue> levels;
  for (const int speed : {0, 1, 2}) {  // slow, medium, fast
    ControlInput in = drive_panel(1.0f, 0.0f);
    in.switches["speed"] = speed;
    sim.set_input(in);
    run_for(sim, 1.5);
    levels.push_back(cue_named(sim.snapshot(), hum));
  }
  INFO(robot << ": gains " << levels[0].gain << " " << levels[1].gain << " " << levels[2].gain << ", pitches "
             << levels[0].pitch << " " << levels[1].pitch << " " << levels[2].pitch);
  CHECK(levels[0].gain > 0.0);
  CHECK(levels[1].gain > levels[0].gain + 0.05);
  CHECK(levels[2].gain > levels[1].gain + 0.05);
  CHECK(levels[1].pitch > levels[0].pitch + 0.05);
  CHECK(levels[2].pitch > levels[1].pitch + 0.05);
  CHECK(levels[2].gain <= 1.0);
  CHECK(levels[0].detail.rfind("drive_speed ", 0) == 0);

  // Stopped again: silent.
  sim.set_input(rest);
  run_for(sim, 1.0);
  CHECK(cue_named(sim.snapshot(), hum).gain == 0.0);
  // The hum is a state, never a one-shot.
  for (const auto& c : sim.take_sound_cues()) CHECK(c.name != hum);
}

TEST_CASE("the arm servos' cue follows the arm's joint rates", "[sim]") {
  Simulation sim(load_robot_description(kRobots + "tracked_eod.yaml"), WorldDescription{});
  ControlInput in = drive_panel(0.0f, 0.0f);
  in.switches["mode"] = 1;
  in.switch_labels["mode"] = "arm";
  sim.set_input(in);
  run_for(sim, 0.3);
  CHECK(cue_named(sim.snapshot(), "arm_servos").gain == 0.0);
  in.axes["arm_x"] = 0.3f;
  sim.set_input(in);
  run_for(sim, 0.3);
  const double slow = cue_named(sim.snapshot(), "arm_servos").gain;
  in.axes["arm_x"] = 1.0f;
  sim.set_input(in);
  run_for(sim, 0.3);
  const double fast = cue_named(sim.snapshot(), "arm_servos").gain;
  INFO("gain at 0.24 rad/s " << slow << ", at 0.8 rad/s " << fast);
  CHECK(slow > 0.0);
  CHECK(fast > slow + 0.1);
  CHECK(fast == Approx(0.5).margin(0.02));  // full_at 0.8 rad/s = the joint's max rate
}

TEST_CASE("a collision sounds the impact cue once per collision, louder for a faster impact", "[sim]") {
  const Impact slow = drive_into_crate(0.3f);
  const Impact fast = drive_into_crate(0.7f);  // 0.84 m/s: under the gain cap
  INFO("slow: impact " << slow.impact_mps << " m/s, gain " << slow.gain << ", " << slow.cues << " cues for "
                       << slow.events << " collisions; fast: impact " << fast.impact_mps << " m/s, gain " << fast.gain
                       << ", " << fast.cues << " cues for " << fast.events << " collisions");
  for (const Impact* run : {&slow, &fast}) {
    CHECK(run->cues >= 1);
    CHECK(run->cues == run->events);  // one cue per collision_started at or above min_impact_mps
    // The first collision is the crate's: gain = 1.0 per m/s of impact (skid4.yaml), capped at 1.
    CHECK(run->gain == Approx(std::min(1.0, run->impact_mps)).margin(0.006));
  }
  CHECK(fast.impact_mps > slow.impact_mps * 1.5);
  CHECK(fast.gain > slow.gain);
}

TEST_CASE("a horn button sounds once per press, and only from a live panel", "[sim]") {
  Simulation sim(load_robot_description(kRobots + "skid4.yaml"), WorldDescription{});
  ControlInput in = drive_panel(0.0f, 0.0f);
  int horns = 0;
  const auto count = [&] {
    for (const auto& c : sim.take_sound_cues()) {
      if (c.name != "horn") continue;
      ++horns;
      CHECK(c.gain == Approx(0.8));
      CHECK(c.detail == "button horn");
    }
  };
  for (const bool press : {true, false, true, true, false}) {
    in.buttons["horn"] = press;
    sim.set_input(in);
    run_for(sim, 0.1);
    count();
  }
  CHECK(horns == 2);
  in.failsafe = true;
  in.buttons["horn"] = false;
  sim.set_input(in);
  run_for(sim, 0.1);
  in.buttons["horn"] = true;
  sim.set_input(in);
  run_for(sim, 0.1);
  count();
  CHECK(horns == 2);  // a failsafe panel's buttons are not trusted
}

TEST_CASE("a joint broken by overload and a door pushed open sound the robot's one-shot cues", "[sim]") {
  SECTION("joint_broken") {
    // As in tracked_robot_test: a shoulder motor upgraded to 450 N·m pressing
    // the gripper into the floor breaks its 300 N·m joint.
    auto robot = load_robot_description(kRobots + "tracked_eod.yaml");
    robot.control.arm->joints[1].max_torque_nm = 450.0;
    Simulation sim(robot, WorldDescription{});
    ControlInput in = drive_panel(0.0f, 0.0f);
    in.switches["mode"] = 1;
    in.switch_labels["mode"] = "arm";
    in.axes["arm_y"] = -1.0f;
    sim.set_input(in);
    int broken = 0;
    std::vector<SoundCue> snaps;
    for (int i = 0; i < 8000; ++i) {
      sim.step();
      for (const auto& e : sim.take_events()) broken += e.kind == SimEventKind::JointBroken;
      for (const auto& c : sim.take_sound_cues())
        if (c.name == "joint_snap") snaps.push_back(c);
    }
    REQUIRE(broken == 1);
    REQUIRE(snaps.size() == 1);
    CHECK(snaps[0].detail.rfind("joint_broken ", 0) == 0);
    CHECK(snaps[0].sample == "metal_snap");
    CHECK(snaps[0].gain == Approx(1.0));
  }
  SECTION("door_opened") {
    // Pushed slowly, door_ab opens (tracked_robot_test); the robot touching it hears it.
    Simulation sim(load_robot_description(kRobots + "tracked_eod.yaml"),
                   load_world_description(std::string(RISE_SOURCE_DIR) + "/sim/worlds/building.yaml"));
    ControlInput in = drive_panel(1.0f, 0.0f);
    in.switches["speed"] = 0;
    in.switch_labels["speed"] = "slow";
    sim.set_input(in);
    double opened_s = -1;
    std::vector<SoundCue> doors;
    for (int i = 0; i < 20000 && opened_s < 0; ++i) {
      sim.step();
      for (const auto& e : sim.take_events())
        if (e.kind == SimEventKind::DoorOpened) opened_s = e.time_s;
      for (const auto& c : sim.take_sound_cues())
        if (c.name == "door") doors.push_back(c);
    }
    REQUIRE(opened_s > 0);
    REQUIRE(doors.size() == 1);
    CHECK(doors[0].time_s == opened_s);
    CHECK(doors[0].detail == "door_opened door_ab");
    CHECK(doors[0].gain == Approx(0.6));
  }
}

TEST_CASE("a bad sounds section is refused with file:line and the key", "[sim]") {
  const std::string good = slurp(kRobots + "tracked_eod.yaml");
  struct Case {
    const char* find;
    const char* replace;
    const char* expected;  // the line is the cue's line in the shipped file (set below)
  };
  const auto c = GENERATE(
      Case{"source: drive_speed, full_at: 1.0,", "source: drive_speed, full_at: 1.0, volume: 2,",
           "sounds.tracks_motor.volume: unknown key"},
      Case{"source: drive_speed,", "source: engine_rpm,",
           "sounds.tracks_motor.source: expected drive_speed, arm_rate or gripper_speed"},
      Case{"gain: [0.2, 0.9]", "gain: [0.2, 1.9]", "sounds.tracks_motor.gain: must be in 0..1"},
      Case{"gain: [0.2, 0.9]", "gain: 0.9", "sounds.tracks_motor.gain: expected [at rest, at full_at]"},
      Case{"silent_below: 0.01, gain: [0.2, 0.9]", "silent_below: 2, gain: [0.2, 0.9]",
           "sounds.tracks_motor.silent_below: must be below full_at"},
      Case{"{on: collision_started,", "{on: collision_begun,", "sounds.impact.on: expected collision_started"},
      Case{"{on: joint_broken, gain: 1.0,", "{on: joint_broken, gain: 1.0, gain_per_mps: 2,",
           "sounds.joint_snap.gain_per_mps: only with on: collision_started"},
      Case{"{on: button, button: horn,", "{on: button,", "sounds.horn.button: missing: which panel button"},
      Case{"{on: door_opened, gain: 0.6,", "{source: drive_speed, on: door_opened, gain: 0.6,",
           "sounds.door: source (continuous) or on (one-shot), not both"});
  std::string text = good;
  const auto at = text.find(c.find);
  REQUIRE(at != std::string::npos);
  text.replace(at, std::string(c.find).size(), c.replace);
  const int line = static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n')) + 1;
  // Named as if beside the shipped file, so that its URDF is found.
  const std::string file = kRobots + "bad.yaml";
  const auto error = error_of([&] { parse_robot_description(text, file); });
  INFO(error);
  CHECK(error.rfind(file + ":" + std::to_string(line) + ": " + c.expected, 0) == 0);

  // arm_rate on a robot without an arm.
  const std::string skid = slurp(kRobots + "skid4.yaml") + "  servos: {source: arm_rate}\n";
  CHECK_THAT(error_of([&] { parse_robot_description(skid, kRobots + "skid.yaml"); }),
             Catch::Matches(".*/skid\\.yaml:[0-9]+: sounds\\.servos\\.source: the robot has no arm"));
}
