#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

#include "sim/simulation.hpp"
#include "sim/urdf_robot.hpp"
#include "tests/sim/sim_panel.hpp"

using namespace rise::sim;

namespace {
const std::string kRobots = std::string(RISE_SOURCE_DIR) + "/sim/robots/";
const std::string kData = std::string(RISE_SOURCE_DIR) + "/tests/sim/data/";

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string replaced(std::string text, const std::string& find, const std::string& replace) {
  const auto at = text.find(find);
  if (at == std::string::npos) throw std::logic_error("test text lacks '" + find + "'");
  return text.replace(at, find.size(), replace);
}

/// A folder for one robot file and its URDF, removed at the end. The same
/// `tag` gives the same folder on every GENERATE run of a test.
struct TempRobot {
  std::filesystem::path dir;
  explicit TempRobot(const std::string& tag)
      : dir(std::filesystem::temp_directory_path() / ("rise_urdf_test_" + std::to_string(::getpid()) + "_" + tag)) {
    std::filesystem::create_directories(dir);
  }
  ~TempRobot() { std::filesystem::remove_all(dir); }
  TempRobot(const TempRobot&) = delete;
  TempRobot& operator=(const TempRobot&) = delete;
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(dir / name) << text;
    return (dir / name).string();
  }
};

std::string load_error(const std::string& yaml_path) {
  return testing::error_of([&] { load_robot_description(yaml_path); });
}

ControlInput arm_panel(float pitch) {
  ControlInput in = testing::drive_panel(0.0f, 0.0f);
  in.switch_labels["mode"] = "arm";
  in.switches["mode"] = 1;
  in.axes = {{"arm_x", 0.0f}, {"arm_y", pitch}, {"arm_twist", 0.0f}};
  return in;
}
}  // namespace

TEST_CASE("a URDF robot file gives the same robot description as its inline form", "[sim]") {
  const std::string robot = GENERATE(std::string("skid4"), std::string("tracked_eod"));
  const auto from_urdf = load_robot_description(kRobots + robot + ".yaml");
  auto inline_form = load_robot_description(kData + robot + "_inline.yaml");
  // The skid-steer's clearance is derived (wheel radius − joint height − half
  // the chassis): equal up to rounding, then the rest must match exactly.
  CHECK(from_urdf.chassis.clearance_m == Approx(inline_form.chassis.clearance_m).margin(1e-12));
  inline_form.chassis.clearance_m = from_urdf.chassis.clearance_m;
  inline_form.file = from_urdf.file;
  REQUIRE(from_urdf.arm.has_value() == (robot == "tracked_eod"));
  CHECK(from_urdf.chassis == inline_form.chassis);
  CHECK(from_urdf.wheels == inline_form.wheels);
  CHECK(from_urdf.arm == inline_form.arm);
  CHECK(from_urdf.control == inline_form.control);
  CHECK(from_urdf == inline_form);
}

TEST_CASE("the shoulder stops at the URDF's joint limit, not at a YAML one", "[sim]") {
  TempRobot t("limit");
  const std::string urdf = slurp(kRobots + "tracked_eod.urdf");
  const std::string upper_45 = "upper=\"0.78539816339744828\" effort=\"120\"";
  REQUIRE(urdf.find(upper_45) != std::string::npos);
  t.write("tracked_eod.urdf", replaced(urdf, upper_45, "upper=\"0.3490658503988659\" effort=\"120\""));  // 20°
  const std::string yaml = t.write("tracked_eod.yaml", slurp(kRobots + "tracked_eod.yaml"));
  const double limit_rad = GENERATE(M_PI / 4, 20 * M_PI / 180);
  const auto robot = load_robot_description(limit_rad == M_PI / 4 ? kRobots + "tracked_eod.yaml" : yaml);
  REQUIRE(robot.control.arm->joints[1].max_rad == Approx(limit_rad).margin(1e-12));
  Simulation sim(robot, WorldDescription{});
  sim.set_input(arm_panel(1.0f));  // 0.6 rad/s up for 3 s: 1.8 rad without a stop
  testing::run_for(sim, 3.0);
  const auto s = sim.snapshot();
  CHECK(s.joints[1].position == Approx(limit_rad).margin(0.02));
  CHECK(s.damage == 0.0);
}

TEST_CASE("a wrong URDF is refused with the robot file's line, the urdf key and the reason", "[sim]") {
  struct Case {
    const char* robot;
    const char* find;
    const char* replace;
    const char* expected;  // after "<yaml>:<line>: urdf: <robot>.urdf: "
  };
  const auto c = GENERATE(
      Case{"tracked_eod", "<robot name=\"tracked_eod\">", "<robot name=\"tracked_eod\"", "liburdfdom: Error reading Attributes."},
      Case{"tracked_eod", "<limit lower=\"-1.0471975511965976\" upper=\"0.78539816339744828\" effort=\"120\" velocity=\"0.6\"/>",
           "", "liburdfdom: Joint [shoulder_pitch] is of type REVOLUTE but it does not specify limits; "
               "joint xml is not initialized correctly"},
      Case{"tracked_eod", "<joint name=\"elbow_pitch\"", "<joint name=\"elbow\"", "no joint 'elbow_pitch'"},
      Case{"tracked_eod", "<geometry><box size=\"0.45 0.06 0.06\"/></geometry>",
           "<geometry><mesh filename=\"upper_arm.stl\"/></geometry>",
           "link 'arm_upper': unsupported collision shape mesh (the simulator needs a box)"},
      Case{"tracked_eod", "<axis xyz=\"0 0 1\"/>", "<axis xyz=\"1 0 0\"/>",
           "joint 'shoulder_yaw' axis is 1 0 0, the simulator's model needs 0 0 1"},
      Case{"tracked_eod", "<mass value=\"50\"/>", "<mass value=\"5\"/>",
           "link 'base_link': inertia ixx+iyy+izz = 5.686667 kg m^2 is not the solid shape's 0.568667 "
           "(the simulator computes inertia from the collision shape)"},
      Case{"skid4", "<geometry><cylinder radius=\"0.12\" length=\"0.08\"/></geometry>",
           "<geometry><sphere radius=\"0.12\"/></geometry>",
           "link 'front_left_wheel': unsupported collision shape sphere (the simulator needs a cylinder)"},
      Case{"skid4", "<origin xyz=\"0.25 -0.31 -0.055\"/>", "<origin xyz=\"0.3 -0.31 -0.055\"/>",
           "joint 'front_right_wheel_joint' origin xyz is 0.3 -0.31 -0.055: the wheels must sit at (±wheelbase/2, "
           "±track/2) at one height, in the order front left, front right, rear left, rear right"},
      // Found with the urdf fuzz target's checks (tests/fuzz/urdf_fuzz.cpp): liburdfdom takes a
      // negative size and the inertia check squares it away, so the simulator got a negative chassis
      // (the fuzzer's own find, a zero size, is the next test).
      Case{"tracked_eod", "<box size=\"0.7 0.4 0.18\"/>", "<box size=\"-0.7 0.4 -0.18\"/>",
           "link 'base_link': the box's sizes must be > 0"},
      Case{"skid4", "<cylinder radius=\"0.12\" length=\"0.08\"/>", "<cylinder radius=\"-0.12\" length=\"0.08\"/>",
           "link 'front_left_wheel': the cylinder's sizes must be > 0"});
  TempRobot t("bad_urdf");
  const std::string name = c.robot;
  t.write(name + ".urdf", replaced(slurp(kRobots + name + ".urdf"), c.find, c.replace));
  const std::string yaml = t.write(name + ".yaml", slurp(kRobots + name + ".yaml"));
  const int line = name == "skid4" ? 4 : 7;
  const std::string error = load_error(yaml);
  CHECK(error == yaml + ":" + std::to_string(line) + ": urdf: " + name + ".urdf: " + c.expected);
}

TEST_CASE("a robot file whose URDF is missing or mixes in inline geometry is refused with the key", "[sim]") {
  TempRobot t("bad_yaml");
  const std::string nope = (t.dir / "nope.urdf").string();
  t.write("tracked_eod.urdf", slurp(kRobots + "tracked_eod.urdf"));
  t.write("skid4.urdf", slurp(kRobots + "skid4.urdf"));
  const std::string tracked = slurp(kRobots + "tracked_eod.yaml");
  const std::string skid = slurp(kRobots + "skid4.yaml");
  struct Case {
    std::string text;
    std::string expected;  // after "<yaml>:"
  };
  const auto c = GENERATE_COPY(
      Case{replaced(tracked, "urdf: tracked_eod.urdf", "urdf: nope.urdf"),
           "7: urdf: nope.urdf: " + nope + ": cannot open: No such file or directory"},
      Case{replaced(tracked, "max_radps: 0.6,", "max_radps: 0.6, max_deg: 30,"),
           "31: control.arm.shoulder_pitch.max_deg: comes from the URDF joint's limit"},
      Case{replaced(tracked, "  joints: [shoulder_yaw,", "  upper_length_m: 0.4\n  joints: [shoulder_yaw,"),
           "20: arm.upper_length_m: unknown key"},
      Case{replaced(tracked, "[shoulder_yaw, shoulder_pitch, elbow_pitch, gripper]", "[shoulder_yaw, shoulder_pitch]"),
           "20: arm.joints: expected a list of 4 URDF joint names"},
      Case{replaced(skid, "  friction: 1.0", "  radius_m: 0.12\n  friction: 1.0"), "7: wheels.radius_m: unknown key"},
      Case{replaced(skid, "wheels:\n", "chassis: {clearance_m: 0.05}\nwheels:\n"),
           "5: chassis: comes from the URDF (clearance from the wheel joints' height)"},
      Case{replaced(skid, "  joints: [front_left_wheel_joint, front_right_wheel_joint, rear_left_wheel_joint, "
                          "rear_right_wheel_joint]\n", ""),
           "6: wheels.joints: missing: the URDF joints of the wheels (fl, fr, rl, rr)"});
  const std::string yaml = t.write("robot.yaml", c.text);
  CHECK(load_error(yaml) == yaml + ":" + c.expected);
}

// Found by the urdf fuzz target (tests/fuzz/urdf_fuzz.cpp, its artifact as it was): a box of
// size 0 whose inertia trace matches (2 = 6 kg x (0 + 1 + 1) / 6) was taken as a chassis.
TEST_CASE("a URDF body of zero or negative size is refused", "[sim]") {
  const std::string urdf =
      R"(<robot name="r"><link name="base"><inertial><mass value="6"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" )"
      R"(iyz="0" izz="0"/></inertial><collision><geometry><box size="0 1 1"/></geometry></collision></link></robot>)";
  CHECK(testing::error_of([&] { parse_urdf_robot(urdf, {}); }) == "link 'base': the box's sizes must be > 0");
  const auto ok = parse_urdf_robot(replaced(replaced(urdf, "\"0 1 1\"", "\"1 1 1\""), "izz=\"0\"", "izz=\"1\""), {});
  CHECK(ok.chassis_size_m == std::array<double, 3>{1, 1, 1});
  CHECK(ok.chassis_mass_kg == 6.0);
}

// Found by the urdf fuzz target: a text ending inside a UTF-8 sequence made
// tinyxml (liburdfdom's parser) read past the end of the string.
TEST_CASE("a URDF that is not whole UTF-8 is refused before liburdfdom reads it", "[sim]") {
  CHECK(testing::error_of([] { parse_urdf_robot("<robot name=\"r\">\n    \xef\xef\xef", {}); }) == "not UTF-8 text");
  CHECK(testing::error_of([] { parse_urdf_robot("<robot name=\"r\xc3\x28\"/>", {}); }) == "not UTF-8 text");
  CHECK(testing::error_of([] { parse_urdf_robot("<robot name=\"r\xc3\xa9\"/>", {}); }) != "not UTF-8 text");
}
