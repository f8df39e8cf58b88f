// The web console's JSON on its own: what the map and the 3D view draw of
// the world, and a RobotState as the pages read it.

#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "instructor/web_json.hpp"
#include "sim/robot_description.hpp"
#include "sim/world_description.hpp"

namespace {
using rise::instructor::robot_json;
using rise::instructor::world_json;

// The boxes of `kind`, in the order world_json lists them.
std::vector<Json::Value> boxes_of(const Json::Value& world, const std::string& kind) {
  std::vector<Json::Value> out;
  for (const auto& b : world["boxes"])
    if (b["kind"].asString() == kind) out.push_back(b);
  return out;
}
}  // namespace

TEST_CASE("the world JSON draws a door closed from its hinge and a staircase as steps and a landing", "[instructor]") {
  rise::sim::WorldDescription w;
  rise::sim::Door door;
  door.name = "door1";
  door.hinge_m = {2.0, 1.0};
  door.width_m = 0.9;
  door.height_m = 2.0;
  door.yaw_rad = M_PI / 2;
  w.doors.push_back(door);
  rise::sim::Stairs stairs;
  stairs.name = "stairs1";
  stairs.start_m = {5.0, 0.0};
  stairs.steps = 3;
  stairs.riser_m = 0.2;
  stairs.tread_m = 0.3;
  stairs.landing_m = 1.0;
  w.stairs.push_back(stairs);

  const Json::Value v = world_json(w);
  const auto doors = boxes_of(v, "door");
  REQUIRE(doors.size() == 1);
  CHECK(doors[0]["name"].asString() == "door1");
  CHECK(doors[0]["center"][0].asDouble() == Approx(2.0).margin(1e-9));
  CHECK(doors[0]["center"][1].asDouble() == Approx(1.45).margin(1e-9));  // half the width along the yaw
  CHECK(doors[0]["center"][2].asDouble() == Approx(1.0).margin(1e-9));
  CHECK(doors[0]["size"][0].asDouble() == Approx(0.9).margin(1e-9));

  const auto steps = boxes_of(v, "stairs");
  REQUIRE(steps.size() == 4);  // three steps and the landing
  CHECK(steps[0]["center"][0].asDouble() == Approx(5.15).margin(1e-9));
  CHECK(steps[0]["size"][2].asDouble() == Approx(0.2).margin(1e-9));
  CHECK(steps[2]["size"][2].asDouble() == Approx(0.6).margin(1e-9));
  CHECK(steps[3]["center"][0].asDouble() == Approx(5.0 + 0.9 + 0.5).margin(1e-9));
  CHECK(steps[3]["size"][0].asDouble() == Approx(1.0).margin(1e-9));
  CHECK(steps[3]["size"][2].asDouble() == Approx(0.6).margin(1e-9));
  CHECK(v["robot_start"].size() == 3);
}

TEST_CASE("the RobotState JSON gives the yaw of the orientation and names the objects", "[instructor]") {
  rise_msgs::RobotState m{};
  m.robot_id = "r1";
  const double yaw = GENERATE(0.0, 0.7, -2.5);
  m.orientation_wxyz[0] = std::cos(yaw / 2);
  m.orientation_wxyz[3] = std::sin(yaw / 2);
  m.num_objects = 1;
  m.object_names = {"crate"};
  m.object_positions_m = {{1.0, 2.0, 0.15}};

  const Json::Value v = robot_json(m);
  CHECK(v["robot_id"].asString() == "r1");
  CHECK(v["yaw"].asDouble() == Approx(yaw).margin(1e-9));
  REQUIRE(v["objects"].size() == 1);
  CHECK(v["objects"][0]["name"].asString() == "crate");
  CHECK(v["objects"][0]["position"][1].asDouble() == Approx(2.0).margin(1e-12));
}

TEST_CASE("a urdf_tree robot's JSON carries its links' visual meshes and its joints; RobotState its joint positions",
          "[instructor]") {
  const auto d = rise::sim::load_robot_description(std::string(RISE_SOURCE_DIR) + "/sim/robots/turtlebot3_burger.yaml");
  const Json::Value v = robot_json(d);
  REQUIRE(v["links"].size() == 5);
  CHECK(v["links"][0]["name"].asString() == "base_link");
  const Json::Value& body = v["links"][0]["visuals"][0];
  CHECK(body["type"].asString() == "mesh");
  CHECK(body["triangles"].size() == 3 * 28);
  CHECK(body["vertices"].size() % 3 == 0);
  CHECK(body["origin"]["xyz"][2].asDouble() == Approx(0.070));
  REQUIRE(v["joints"].size() == 4);
  Json::Value left;
  for (const auto& j : v["joints"])
    if (j["name"].asString() == "wheel_left_joint") left = j;
  CHECK(left["type"].asString() == "continuous");
  CHECK(v["links"][left["child"].asUInt()]["name"].asString() == "wheel_left_link");
  CHECK(left["parent"].asUInt() == 0);
  // The fixed-model robots carry no tree.
  CHECK_FALSE(robot_json(rise::sim::load_robot_description(std::string(RISE_SOURCE_DIR) + "/sim/robots/skid4.yaml"))
                  .isMember("links"));

  rise_msgs::RobotState m{};
  m.num_joints = 1;
  m.joint_names = {"wheel_left_joint"};
  m.joint_positions = {12.5};
  m.joint_velocities = {1.0};
  m.joint_efforts = {0.0};
  const Json::Value s = robot_json(m);
  REQUIRE(s["joints"].size() == 1);
  CHECK(s["joints"][0]["name"].asString() == "wheel_left_joint");
  CHECK(s["joints"][0]["position"].asDouble() == Approx(12.5));
}

TEST_CASE("the SoundCue JSON carries what the trainee page plays", "[instructor]") {
  rise_msgs::SoundCue m{};
  m.utime = 1700000000123456;
  m.sim_time_s = 2.5;
  m.name = "wheel_motors";
  m.sample = "wheel_motor_whine";
  m.continuous = true;
  m.gain = 0.25f;
  m.pitch = 1.5f;
  m.detail = "drive_speed 0.620";
  const Json::Value v = rise::instructor::sound_cue_json(m);
  CHECK(v["utime"].asInt64() == 1700000000123456);
  CHECK(v["name"].asString() == "wheel_motors");
  CHECK(v["sample"].asString() == "wheel_motor_whine");
  CHECK(v["continuous"].asBool());
  CHECK(v["gain"].asDouble() == Approx(0.25));
  CHECK(v["pitch"].asDouble() == Approx(1.5));
  CHECK(v["detail"].asString() == "drive_speed 0.620");
}

TEST_CASE("the PanelFeedback JSON gives the LEDs and displays by name and the buzzer in words", "[instructor]") {
  rise_msgs::PanelFeedback m{};
  m.utime = 42;
  m.led_names = {"power", "fault"};
  m.led_on = {1, 0};
  m.num_leds = 2;
  m.display_names = {"speed"};
  m.display_values = {1.25f};
  m.num_displays = 1;
  m.buzzer = 2;
  m.rumble = 0.5f;
  const auto v = rise::instructor::panel_feedback_json(m);
  CHECK(v["leds"]["power"].asBool());
  CHECK(v["leds"]["power"].isBool());
  CHECK_FALSE(v["leds"]["fault"].asBool());
  CHECK(v["displays"]["speed"].asDouble() == Approx(1.25));
  CHECK(v["buzzer"].asString() == "beep");
  CHECK(v["rumble"].asDouble() == Approx(0.5));
  m.buzzer = 0;
  CHECK(rise::instructor::panel_feedback_json(m)["buzzer"].asString() == "off");
}

// Found by the lcm_messages fuzz target (tests/fuzz/lcm_messages_fuzz.cpp):
// a SoundCue with pitch +inf from the multicast group became "1e+9999", which
// the page's JSON.parse reads as Infinity (WebAudio throws on it). JSON has no
// infinity: a non-finite number is null, as jsoncpp writes NaN.
TEST_CASE("a non-finite number in a message's JSON is null", "[instructor]") {
  rise_msgs::SoundCue cue{};
  cue.name = "motor", cue.pitch = INFINITY, cue.gain = -INFINITY;
  const std::string text = rise::instructor::json_text(rise::instructor::sound_cue_json(cue));
  CHECK(text.find("\"pitch\":null") != std::string::npos);
  CHECK(text.find("\"gain\":null") != std::string::npos);
  CHECK(text.find("1e+9999") == std::string::npos);
  Json::Value nested;
  nested["a"][0]["b"] = std::nan("");
  nested["a"][1] = 1.5;
  CHECK(rise::instructor::json_text(nested) == R"({"a":[{"b":null},1.5]})");
}
