#include <catch2/catch.hpp>

#include <cmath>

#include "sim/app/scripted_console.hpp"
#include "sim/training/task_description.hpp"
#include "sim/training/task_executor.hpp"
#include "tests/training/training_files.hpp"

using namespace rise::sim::training;
using rise::test::src;
using Catch::Matchers::Contains;

namespace {

// Runs a task file with its console script in-process; every fired event's
// points add up to the score.
TaskResult play(const std::string& task_file) {
  const auto task = load_task_description(task_file);
  std::optional<rise::trainer::ScriptedConsole> console;
  if (!task.console_script.empty()) console.emplace(task.panel_file, task.console_script);
  auto r = rise::trainer::play_task(task, console ? &*console : nullptr);
  for (const auto& e : r.events) UNSCOPED_INFO(e.time_s << " s " << e.name << " " << e.points << " " << e.detail);
  int sum = 0;
  for (const auto& e : r.events) sum += e.points;
  CHECK(sum == r.score);
  for (const auto& e : task.events) CHECK(r.counts.at(e.name) == static_cast<int>(std::count_if(
                                          r.events.begin(), r.events.end(), [&](const FiredEvent& f) { return f.name == e.name; })));
  return r;
}

std::string parse_error(const std::string& text) {
  try {
    parse_task_description(text, "bad_task.yaml");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "(no error)";
}

const std::string kHead =
    "task: t\nrobot: r.yaml\nworld: w.yaml\n";

}  // namespace

TEST_CASE("the metro transport task file loads with its events, start pose and end conditions", "[training]") {
  const auto t = load_task_description(src("sim/training/examples/metro_transport.yaml"));
  CHECK(t.name == "metro_transport");
  CHECK(t.robot_file == src("sim/robots/tracked_eod.yaml"));
  CHECK(t.world_file == src("sim/worlds/building.yaml"));
  REQUIRE(t.start);
  CHECK(t.start->xy_m[0] == Approx(5.60).margin(1e-9));
  CHECK(t.start->yaw_rad == Approx(-61.7 * M_PI / 180).margin(1e-9));
  CHECK(t.time_limit_s == 60);
  REQUIRE(t.events.size() == 8);
  CHECK(t.events[0].kind == TaskEventKind::ObjectInRegion);
  CHECK(t.events[0].hold_s == 1.0);
  CHECK(t.events[6].kind == TaskEventKind::Collision);
  CHECK(t.events[6].max_count == 0);
  CHECK(t.events[7].per_second);
  CHECK(t.end_on == std::vector<std::string>{"object_delivered", "tipped_over"});
  CHECK_NOTHROW(check_against_world(t, rise::sim::load_world_description(t.world_file)));
}

TEST_CASE("bad task files are refused naming the file, line and key", "[training]") {
  SECTION("an unknown key") {
    CHECK_THAT(parse_error(kHead + "events:\n  - {name: a, kind: time_exceeded, after_s: 1, pionts: 3}\n"),
               Contains("bad_task.yaml:5: events[0].pionts: unknown key"));
  }
  SECTION("an unknown kind") {
    CHECK_THAT(parse_error(kHead + "events:\n  - {name: a, kind: explode}\n"),
               Contains("bad_task.yaml:5: events[0].kind: unknown kind 'explode'"));
  }
  SECTION("a kind without what it needs") {
    CHECK_THAT(parse_error(kHead + "events:\n  - {name: a, kind: object_in_region, region: r}\n"),
               Contains("bad_task.yaml:5: events[0].object: missing (kind object_in_region needs it)"));
  }
  SECTION("a key that is not for the kind") {
    CHECK_THAT(parse_error(kHead + "events:\n  - {name: a, kind: touch_object, object: o, hold_s: 2}\n"),
               Contains("bad_task.yaml:5: events[0].hold_s: not for kind touch_object"));
  }
  SECTION("an end condition on an unknown event") {
    CHECK_THAT(parse_error(kHead + "events:\n  - {name: a, kind: robot_disabled}\nend_on: [a, b]\n"),
               Contains("bad_task.yaml:6: end_on[1]: unknown event 'b'"));
  }
  SECTION("a duplicate event name") {
    CHECK_THAT(parse_error(kHead + "events:\n  - {name: a, kind: robot_disabled}\n  - {name: a, kind: robot_damaged}\n"),
               Contains("bad_task.yaml:6: events[1].name: duplicate event name 'a'"));
  }
  SECTION("a time limit that is not positive") {
    CHECK_THAT(parse_error(kHead + "time_limit_s: 0\nevents:\n  - {name: a, kind: robot_disabled}\n"),
               Contains("bad_task.yaml:4: time_limit_s: must be > 0"));
    CHECK_THAT(parse_error(kHead + "events:\n  - {name: a, kind: time_exceeded, after_s: -1}\n"),
               Contains("bad_task.yaml:5: events[0].after_s: must be > 0"));
  }
  SECTION("a missing robot") {
    CHECK_THAT(parse_error("task: t\nworld: w.yaml\nevents: []\n"), Contains("bad_task.yaml:1: robot: missing"));
  }
  SECTION("a region the world does not have") {
    const auto t = parse_task_description(kHead + "events:\n  - {name: a, kind: reach_region, region: moon}\n", "t.yaml");
    CHECK_THROWS_WITH(check_against_world(t, rise::sim::load_world_description(src("sim/worlds/building.yaml"))),
                      Contains("t.yaml:5: events[0].region: no region 'moon'"));
  }
}

TEST_CASE("every event kind fires and scores in scripted runs of the simulator", "[training]") {
  const auto dir = rise::test::temp_dir("kinds");
  const auto w = [&](const std::string& name, const std::string& text) { return rise::test::write_file(dir, name, text); };
  SECTION("transport: object in region, touch, world region reached, time exceeded") {
    const auto script = w("push.txt", "0.0 mode drive\n0.0 speed medium\n0.2 deadman pressed\n0.5 drive_y 1.0\n9.5 drive_y 0.0\n");
    const auto r = play(w("push.yaml", rise::test::task_header("push", "{xy_m: [5.60, 2.25], yaw_deg: -61.7}", 11, script) +
                                           "events:\n"
                                           "  - {name: delivered, kind: object_in_region, object: hazardous_object, region: neutralization_area, hold_s: 1.0, points: 20}\n"
                                           "  - {name: in_area, kind: reach_region, region: neutralization_area, points: 3}\n"
                                           "  - {name: touched, kind: touch_object, object: hazardous_object, points: 1}\n"
                                           "  - {name: late, kind: time_exceeded, after_s: 5, points: -5}\n"));
    CHECK(r.counts.at("delivered") == 1);
    CHECK(r.counts.at("in_area") == 1);
    CHECK(r.counts.at("touched") >= 1);
    CHECK(r.counts.at("late") == 1);
    CHECK(r.end_reason == "time limit");
    CHECK(r.time_s == Approx(11).margin(0.03));
    CHECK(r.object_tracks.at("hazardous_object").back().y_m < -1.0);
  }
  SECTION("collisions per contact and per second, a broken arm joint") {
    // The robot straddles the staircase's side: its arm jams against the
    // steps and the shoulder breaks; its track stays on the steps.
    const auto script = w("jam.txt", "0.0 mode drive\n0.2 deadman pressed\n");
    const auto r = play(w("jam.yaml", rise::test::task_header("jam", "{xy_m: [0.6, 4.8], yaw_deg: 0}", 4, script) +
                                          "events:\n"
                                          "  - {name: bump, kind: collision, points: -1}\n"
                                          "  - {name: pressed, kind: collision, per: second, points: -2}\n"
                                          "  - {name: broken, kind: robot_damaged, points: -10}\n"));
    CHECK(r.counts.at("bump") >= 1);
    CHECK(r.counts.at("pressed") >= 1);
    CHECK(r.counts.at("broken") >= 1);
    CHECK(r.damage >= 0.25);
  }
  SECTION("neutralize: the gripper on the object, and within a distance of it") {
    const auto r = play(src("sim/training/examples/neutralize_object.yaml"));
    CHECK(r.counts.at("neutralized") == 1);
    CHECK(r.counts.at("gripper_near") == 1);
    CHECK(r.end_reason == "event neutralized");
    CHECK(r.success);
  }
  SECTION("disabled: the skid-steer tips over off the staircase's side") {
    const auto script = w("tip.txt", "0.0 mode drive\n0.0 speed fast\n0.0 deadman pressed\n0.0 drive_y 1.0\n");
    const auto r = play(w("tip.yaml", rise::test::task_header("tip", "{xy_m: [1.0, 4.75], yaw_deg: 0}", 6, script, "skid4") +
                                          "events:\n  - {name: tipped, kind: robot_disabled, points: -20}\nend_on: [tipped]\n"));
    CHECK(r.counts.at("tipped") == 1);
    CHECK(r.end_reason == "event tipped");
    CHECK(r.score == -20);
    CHECK_FALSE(r.success);  // no success list: ended by a penalty event
  }
}

TEST_CASE("the executor ends at the time limit, counts from the first input and keeps goals to one firing", "[training]") {
  const auto world = rise::sim::load_world_description(src("sim/worlds/building.yaml"));
  auto task = parse_task_description(kHead +
                                         "time_limit_s: 2\nevents:\n"
                                         "  - {name: in, kind: reach_region, region: neutralization_area, points: 5}\n"
                                         "  - {name: hit, kind: collision, except: [door_ab], points: -1}\n"
                                         "success: [in]\n",
                                     "t.yaml");
  TaskExecutor x(task, world, "r1");
  RobotSample s;
  s.time_s = 10.0;  // a sim that has run before the task
  x.on_state(s);
  x.on_sim_event({10.5, "region_entered", "r1", "neutralization_area", ""});
  x.on_sim_event({10.6, "region_entered", "r1", "neutralization_area", ""});  // again: a goal fires once
  x.on_sim_event({10.7, "region_entered", "r2", "neutralization_area", ""});  // another robot
  x.on_sim_event({10.8, "collision_started", "chassis", "wall_east", "impact 0.3 m/s"});
  x.on_sim_event({10.9, "collision_started", "chassis", "door_ab", ""});      // excepted
  x.on_sim_event({11.0, "collision_started", "r2/chassis", "wall_east", ""}); // another robot's part
  CHECK_FALSE(x.finished());
  s.time_s = 12.0;
  x.on_state(s);
  REQUIRE(x.finished());
  const auto& r = x.result();
  CHECK(r.end_reason == "time limit");
  CHECK(r.time_s == Approx(2.0));
  CHECK(r.counts.at("in") == 1);
  CHECK(r.counts.at("hit") == 1);
  CHECK(r.score == 4);
  CHECK(r.success);
  CHECK(r.events.at(0).time_s == Approx(0.5));
  CHECK(x.take_fired().size() == 2);
  x.on_sim_event({12.5, "region_entered", "r1", "neutralization_area", ""});
  CHECK(x.result().events.size() == 2);  // nothing after the end
}
