// The Robot Builder in Debian's chromium (playwright-core), by clicks and
// typing (tests/instructor/browser/robot_builder_check.cjs), on a copy of
// skid4.yaml and its URDF in a scratch folder: the 3D view draws the robot's
// parts, a bad limit shows the loader's error inline with line and key, the
// top speed 1.2 → 0.3 m/s is saved in place (comments kept), and "Test
// drive" runs rise-sim with the saved file on the sandbox station, driven
// through the embedded virtual panel: this test measures the speed from
// RobotState over LCM while the stick is held full forward — it must reach
// about 0.3 m/s, never near the old 1.2.

#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>

// Before httplib.h: its <resolv.h> defines _res, a parameter name in Eigen.
#include "sim/robot_description.hpp"

#include "browser_support.hpp"
#include "web_peer.hpp"

namespace fs = std::filesystem;
using namespace rise::instructor_test;
using rise::process::ChildProcess;

namespace {

// The most frequent forward speed of the samples after the first second of
// the hold (the robot's cruise), and the highest.
std::pair<double, double> cruise_and_peak(const std::vector<rise_msgs::RobotState>& states, int64_t from_us,
                                          int64_t to_us) {
  std::vector<double> v;
  for (const auto& s : states)
    if (s.utime >= from_us + 1'500'000 && s.utime <= to_us) v.push_back(s.linear_velocity_mps[0]);
  if (v.empty()) return {0.0, 0.0};
  std::sort(v.begin(), v.end());
  return {v[v.size() / 2], v.back()};
}

}  // namespace

TEST_CASE("the Robot Builder: a motor limit edited by typing, saved in place, and the test drive goes at it",
          "[instructor][robot_builder]") {
  if (const auto why = missing_browser(); !why.empty()) {
    WARN("skipped: " << why);
    return;
  }
  char tmpl[] = "/tmp/rise-robot-builder-XXXXXX";
  const fs::path dir = ::mkdtemp(tmpl);
  const fs::path robots = dir / "robots";
  fs::create_directories(robots);
  for (const char* f : {"skid4.yaml", "skid4.urdf", "tracked_eod.yaml", "tracked_eod.urdf"})
    fs::copy_file(kSource + "/sim/robots/" + f, robots / f);
  const fs::path file = robots / "skid4.yaml";
  const std::string shipped = read_file(file.string());
  const std::string station = "robot_sandbox";  // the Robot Builder's test drive station
  BuilderServer server(dir, dir, {"--robots", robots.string()});
  INFO(read_file((dir / "server.log").string()));
  REQUIRE(server.up);
  TraineePeer peer(station);
  REQUIRE(peer.good());

  const int hold_s = 6;
  ChildProcess node({"/usr/bin/node", kSource + "/tests/instructor/browser/robot_builder_check.cjs", server.base(),
                     server.token, screens_dir(), kWeb, robots.string(), std::to_string(hold_s)},
                    (dir / "robot_check.log").string());
  // RobotState arrives here while the page drives; the hold's start and end
  // are the check's log lines.
  int64_t hold_start = 0, hold_end = 0;
  peer.wait_until([&] { return !node.running(); }, 150000, [&] {
    const std::string log = read_file((dir / "robot_check.log").string());
    if (!hold_start && log.find("HOLD start") != std::string::npos) hold_start = rise::msgs::wall_us();
    if (!hold_end && log.find("HOLD end") != std::string::npos) hold_end = rise::msgs::wall_us();
  });
  if (node.running()) node.stop();
  const int node_code = node.wait_for(1000);
  const auto r = read_result((dir / "robot_check.log").string());
  INFO(read_file((dir / "robot_check.log").string()));
  REQUIRE(node_code == 0);
  REQUIRE_FALSE(r.isMember("error"));
  CHECK(r["page_errors"].size() == 0);
  CHECK(r["status"].asInt() == 200);
  CHECK(r["opened"]["cls"].asString() == "ok");
  CHECK(r["nav"].size() == 6);  // the five builders and the console
  // The 3D view drew the robot's URDF links with the wheels' joint axes, the laser's fan and the camera.
  const std::string parts = text(r["parts"]);
  CHECK(parts.find("\"laser\"") != std::string::npos);
  CHECK(parts.find("\"camera:front\"") != std::string::npos);
  CHECK(parts.find("\"axis:front_left_wheel_joint\"") != std::string::npos);
  CHECK(parts.find("\"front_left_wheel\"") != std::string::npos);
  CHECK(r["view_note"].asString().find("skid_steer · 5 links, 4 joints · laser 270° · 1 camera(s)") != std::string::npos);
  CHECK(r["view_stats"]["variance"].asDouble() > 10);
  CHECK(r["max_mps_before"].asString() == "1.2");
  CHECK(text(r["axis_choices"]).find("\"drive_y\"") != std::string::npos);
  // -1: the loader's words beside the value, with the line and key, and no saving.
  CHECK(r["bad_inline"].asString() == "12: control.linear.max_mps: must be > 0");
  CHECK(r["bad_list"].size() == 1);
  CHECK(r["bad_save_disabled"].asBool());
  CHECK(text(r["horn_choices"]).find("horn (not on the panel)") != std::string::npos);
  CHECK(r["saved_state"].asString().rfind("saved", 0) == 0);
  // Saved in place: the two values changed, every other line (comments too) as shipped.
  const std::string disk = read_file(file.string());
  CHECK(disk == r["disk_after_save"].asString());
  std::string expected = shipped;
  expected.replace(expected.find("max_mps: 1.2"), 12, "max_mps: 0.3");
  expected.replace(expected.find("button: horn"), 12, "button: gripper_open");
  CHECK(disk == expected);
  const auto d = rise::sim::load_robot_description(file.string());
  CHECK(d.control.linear.max == 0.3);

  // The test drive: rise-sim ran the saved file (rise-sim --robot FILE) and
  // the virtual panel's full forward stick drove it at the new limit.
  CHECK(r["drive_state"].asString().find("rise-sim runs skid4.yaml on station " + station) != std::string::npos);
  REQUIRE(hold_start > 0);
  REQUIRE(hold_end > hold_start);
  const auto [cruise, peak] = cruise_and_peak(peer.robot, hold_start, hold_end);
  INFO("cruise " << cruise << " m/s, peak " << peak << " m/s, " << peer.robot.size() << " states");
  CHECK(cruise > 0.25);
  CHECK(cruise < 0.35);
  CHECK(peak < 0.45);  // the old limit, 1.2 m/s, is nowhere near
  double page_max = 0;
  for (const auto& s : r["page_speeds"]) page_max = std::max(page_max, s.asDouble());
  CHECK(page_max > 0.25);
  CHECK(page_max < 0.45);
  CHECK(r["drive_stats"]["variance"].asDouble() > 10);
  // The tracked robot from the list: belts, arm joint axes, both cameras; its motor and break limits listed.
  const std::string tracked = text(r["tracked_parts"]);
  for (const char* part : {"\"tracks\"", "\"laser\"", "\"camera:chase\"", "\"axis:shoulder_yaw\"", "\"axis:gripper\""})
    CHECK(tracked.find(part) != std::string::npos);
  CHECK(r["tracked_note"].asString().find("tracked · ") == 0);
  const std::string motors = text(r["tracked_motors"]);
  CHECK(motors.find("control.arm.elbow_pitch.break_torque_nm") != std::string::npos);
  CHECK(motors.find("tracks.max_speed_mps") != std::string::npos);
  CHECK(motors.find("control.arm.gripper.max_force_n") != std::string::npos);
  // Stopped: no robot states on the station any more.
  const std::size_t seen = peer.robot.size();
  peer.wait_until([] { return false; }, 1500);
  const std::size_t after_stop = peer.robot.size();
  peer.wait_until([] { return false; }, 1000);
  CHECK(peer.robot.size() == after_stop);
  CHECK(seen > 100);
  fs::remove_all(dir);
}
