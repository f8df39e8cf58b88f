// kind: urdf_tree — any URDF as a tree of ODE bodies and joints, its joints
// driven by the panel controls the robot file maps to them by name; meshes
// (STL, COLLADA) read through assimp. The shipped TurtleBot3 Burger-like
// robot drives; the pan_tilt rig (tests/sim/data) moves one joint per
// control mode and holds its limits.

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <unistd.h>

#include "sim/mesh_file.hpp"
#include "sim/simulation.hpp"
#include "sim/urdf_tree.hpp"
#include "tests/sim/sim_panel.hpp"

using namespace rise::sim;
using rise::sim::testing::drive_panel;
using rise::sim::testing::error_of;
using rise::sim::testing::run_for;

namespace {
const std::string kRobots = std::string(RISE_SOURCE_DIR) + "/sim/robots/";
const std::string kData = std::string(RISE_SOURCE_DIR) + "/tests/sim/data/";

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

const JointState& joint(const RobotSnapshot& s, const std::string& name) {
  for (const auto& j : s.joints)
    if (j.name == name) return j;
  throw std::logic_error("no joint state '" + name + "'");
}

/// The pan_tilt rig's panel: dead-man held, mode = drive, the arm axes and buttons.
ControlInput rig_panel(float pan, float tilt, float spin, bool open = false, bool close = false) {
  ControlInput in = drive_panel(0, 0);
  in.axes = {{"arm_x", pan}, {"arm_y", tilt}, {"arm_twist", spin}};
  in.buttons = {{"estop", false}, {"gripper_open", open}, {"gripper_close", close}};
  return in;
}

/// Runs `seconds` and returns the largest value joint `name` reached.
double run_watching(Simulation& sim, double seconds, const std::string& name) {
  double peak = -INFINITY;
  for (int i = 0; i < static_cast<int>(seconds * 1000); ++i) {
    sim.step();
    peak = std::max(peak, joint(sim.snapshot(), name).position);
  }
  return peak;
}

/// A robot file and URDF in a temporary folder (the mesh tests' files beside them).
struct TempRobot {
  std::filesystem::path dir;
  explicit TempRobot(const std::string& tag)
      : dir(std::filesystem::temp_directory_path() / ("rise_urdf_tree_test_" + std::to_string(::getpid()) + "_" + tag)) {
    std::filesystem::create_directories(dir);
    std::filesystem::copy_file(kData + "cube.dae", dir / "cube.dae");
  }
  ~TempRobot() { std::filesystem::remove_all(dir); }
  std::string write(const std::string& yaml, const std::string& urdf) const {
    std::ofstream(dir / "pan_tilt.urdf") << urdf;
    std::ofstream(dir / "robot.yaml") << yaml;
    return (dir / "robot.yaml").string();
  }
};

std::string replaced(std::string text, const std::string& find, const std::string& replace) {
  const auto at = text.find(find);
  if (at == std::string::npos) throw std::logic_error("test text lacks '" + find + "'");
  return text.replace(at, find.size(), replace);
}

}  // namespace

TEST_CASE("the TurtleBot3 Burger robot file loads its URDF as a tree with its STL meshes", "[sim]") {
  const RobotDescription d = load_robot_description(kRobots + "turtlebot3_burger.yaml");
  REQUIRE(d.kind == RobotKind::UrdfTree);
  REQUIRE(d.tree);
  const UrdfTree& t = *d.tree;
  REQUIRE(t.links.size() == 5);
  CHECK(t.links[0].name == "base_link");
  REQUIRE(t.joints.size() == 4);
  const UrdfJoint& left = t.joints[t.joint_index("wheel_left_joint")];
  CHECK(left.type == UrdfJointType::Continuous);
  CHECK(left.effort == Approx(1.5));
  CHECK(left.velocity == Approx(6.67));
  CHECK(t.joints[t.joint_index("caster_back_joint")].type == UrdfJointType::Fixed);
  // The body's collision mesh: an octagonal prism, 6 + 6 cap and 16 side triangles.
  const UrdfShape& body = t.links[0].collisions.at(0);
  REQUIRE(body.type == UrdfShapeType::Mesh);
  CHECK(body.mesh.triangle_count() == 28);
  CHECK(t.links[0].visuals.at(0).mesh.triangle_count() == 28);
  REQUIRE(d.control.joints.size() == 2);
  CHECK(d.control.joints[0].max_effort == Approx(1.5));  // from the URDF
  CHECK(d.control.joints[1].mix->invert);
}

TEST_CASE("the TurtleBot3 Burger drives forward and turns under the panel, and stops without the dead-man", "[sim]") {
  Simulation sim(load_robot_description(kRobots + "turtlebot3_burger.yaml"), WorldDescription{});
  run_for(sim, 0.5);  // settle onto the ground
  const RobotSnapshot rest = sim.snapshot();
  CHECK(rest.position_m[2] == Approx(0.010).margin(0.003));  // base_link 10 mm up
  CHECK(rest.wheels.empty());
  REQUIRE(rest.joints.size() == 2);  // the moving joints only

  sim.set_input(drive_panel(1.0f, 0.0f));
  run_for(sim, 3.0);
  const RobotSnapshot fwd = sim.snapshot();
  // 0.22 m/s at full stick: about 0.6 m in 3 s after spin-up.
  CHECK(fwd.position_m[0] - rest.position_m[0] == Approx(0.63).margin(0.08));
  CHECK(std::fabs(fwd.position_m[1]) < 0.03);
  CHECK(joint(fwd, "wheel_left_joint").velocity == Approx(6.67).margin(0.1));
  CHECK(joint(fwd, "wheel_right_joint").velocity == Approx(6.67).margin(0.1));
  CHECK(joint(fwd, "wheel_left_joint").position > 15.0);
  CHECK(fwd.motors_enabled);
  CHECK(fwd.odometry.position_m[0] == Approx(fwd.position_m[0]).margin(0.05));

  sim.set_input(drive_panel(0.0f, 1.0f));  // stick right: turn right on the spot
  const double yaw0 = sim.snapshot().yaw_rad();
  run_for(sim, 0.5);
  const RobotSnapshot turn = sim.snapshot();
  CHECK(turn.yaw_rad() - yaw0 < -0.3);
  CHECK(joint(turn, "wheel_left_joint").velocity > 3.0);
  CHECK(joint(turn, "wheel_right_joint").velocity < -3.0);

  ControlInput released = drive_panel(1.0f, 0.0f);
  released.deadman = false;
  sim.set_input(released);
  run_for(sim, 1.0);
  const RobotSnapshot stop = sim.snapshot();
  CHECK_FALSE(stop.motors_enabled);
  CHECK(stop.speed_mps() < 0.01);
  CHECK(std::fabs(joint(stop, "wheel_left_joint").velocity) < 0.05);
}

TEST_CASE("urdf_tree joints follow position, velocity and effort controls and hold their limits", "[sim]") {
  Simulation sim(load_robot_description(kData + "pan_tilt.yaml"), WorldDescription{});
  run_for(sim, 0.3);
  REQUIRE(sim.snapshot().joints.size() == 4);  // pan, tilt, slide, spin (tip_joint is fixed)

  SECTION("position: the stick's target, clamped to the URDF limit") {
    sim.set_input(rig_panel(0.5f, 0, 0));
    run_for(sim, 1.5);
    CHECK(joint(sim.snapshot(), "pan").position == Approx(0.75).margin(0.02));
    // Pan turns the child about +z: the slide's tip swings to +y.
    const auto links = sim.T_world_links();
    REQUIRE(links.size() == 6);  // base, pan_link, tilt_link, slider, tip, rotor
    CHECK(links[4].translation().y() > 0.1);  // "tip": 0.25 m out at 0.75 rad
    sim.set_input(rig_panel(1.0f, 0, 0));
    CHECK(run_watching(sim, 1.5, "pan") < 1.0 + 0.02);
    CHECK(joint(sim.snapshot(), "pan").position == Approx(1.0).margin(0.02));
    ControlInput released = rig_panel(-1.0f, 0, 0);
    released.deadman = false;  // not allowed: holds where it is
    sim.set_input(released);
    run_for(sim, 0.5);
    CHECK(joint(sim.snapshot(), "pan").position == Approx(1.0).margin(0.02));
  }
  SECTION("velocity: the stick's rate, up to the joint's stop") {
    sim.set_input(rig_panel(0, 1.0f, 0));
    run_for(sim, 0.3);
    CHECK(joint(sim.snapshot(), "tilt").velocity == Approx(1.0).margin(0.05));
    // Gravity pulls the arm about +y (down); the motor holds it back: its
    // effort along the URDF axis is negative.
    // 0.3 kg at 0.1 m and 0.1 kg at 0.2 m, tilted 0.3 rad: 0.477 N·m · cos 0.3.
    CHECK(joint(sim.snapshot(), "tilt").effort == Approx(-0.455).margin(0.05));
    CHECK(run_watching(sim, 1.5, "tilt") < 0.8 + 0.02);
    CHECK(joint(sim.snapshot(), "tilt").position == Approx(0.8).margin(0.02));
    // Tilting about +y lowers the slide's tip.
    CHECK(sim.T_world_links()[4].translation().z() < sim.T_world_links()[2].translation().z() - 0.1);
  }
  SECTION("buttons: plus opens the slide to its upper limit, minus closes it to the lower one") {
    sim.set_input(rig_panel(0, 0, 0, true, false));
    run_for(sim, 1.0);
    CHECK(joint(sim.snapshot(), "slide").position == Approx(0.05).margin(0.005));
    CHECK(run_watching(sim, 2.0, "slide") < 0.1 + 0.003);
    CHECK(joint(sim.snapshot(), "slide").position == Approx(0.1).margin(0.003));
    sim.set_input(rig_panel(0, 0, 0, false, true));
    run_for(sim, 3.0);
    CHECK(joint(sim.snapshot(), "slide").position == Approx(0.0).margin(0.003));
  }
  SECTION("effort: a torque that spins the rotor up; e-stop lets it coast") {
    sim.set_input(rig_panel(0, 0, 1.0f));
    run_for(sim, 0.02);
    const double spun = joint(sim.snapshot(), "spin").velocity;
    CHECK(spun > 10.0);  // 0.2 N·m on 1.6e-4 kg m²: 1250 rad/s² (less the base's share)
    ControlInput stopped = rig_panel(0, 0, 1.0f);
    stopped.buttons["estop"] = true;
    sim.set_input(stopped);
    run_for(sim, 0.02);
    CHECK(joint(sim.snapshot(), "spin").velocity == Approx(spun).epsilon(0.1));  // no torque, no brake
  }
}

TEST_CASE("assimp reads STL and COLLADA meshes, COLLADA's unit and up axis applied", "[sim]") {
  const TriangleMesh cube = read_mesh_file(kData + "cube.dae");
  CHECK(cube.triangle_count() == 12);
  float lo = INFINITY, hi = -INFINITY;
  for (float v : cube.vertices_m) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  CHECK(lo == Approx(-0.5f));  // 50 cm
  CHECK(hi == Approx(0.5f));
  // STL round trip through our writer, scaled.
  const TriangleMesh stl = parse_mesh(binary_stl(cube), "stl", {2, 2, 2});
  CHECK(stl.triangle_count() == 12);
  float top = -INFINITY;
  for (float v : stl.vertices_m) top = std::max(top, v);
  CHECK(top == Approx(1.0f));
  CHECK(error_of([] { parse_mesh("solid nothing\nendsolid\n", "stl"); }).find("mesh") == 0);
  const std::string cut = binary_stl(cube).substr(0, 84 + 50 * 5);  // says 12 triangles, holds 5
  CHECK(error_of([&] { parse_mesh(cut, "stl"); }).find("mesh: not an STL") == 0);
  // COLLADA is checked and written anew before assimp 5.2 reads it: a wrong
  // count, index or reference made its reader ask for 2.4 GB, follow a null
  // pointer or abort (the mesh fuzz target's finds). Each is refused naming
  // the line. cube.dae's <p> is on line 26, its <float_array> on 14.
  const std::string dae = slurp(kData + "cube.dae");
  const auto edited = [&dae](const std::string& from, const std::string& to) {
    std::string s = dae;
    s.replace(s.find(from), from.size(), to);
    return parse_mesh(s, "dae");
  };
  CHECK(error_of([&] { edited("1 2 6 1 6 5", "1 2 xx 1 6 5"); }) ==
        "mesh:26: <p> index \"xx\" is not a count (up to 9 digits)");
  CHECK(error_of([&] { edited("1 2 6 1 6 5", "1 2 6\v1 6 5"); }) == "mesh:26: not XML: PCDATA invalid Char value 11");
  CHECK(error_of([&] { edited(" count=\"24\"", ""); }) == "mesh:14: <float_array count> must be the count of its numbers, 24");
  CHECK(error_of([&] { edited(" count=\"24\"", " count=\"00\""); }) ==
        "mesh:14: <float_array count> must be the count of its numbers, 24");
  CHECK(error_of([&] { edited("<triangles count=\"12\">", "<triangles count=\"11\">"); }) ==
        "mesh:26: <triangles count=\"11\"> needs 33 × 1 indices in its <p>, not 36");
  CHECK(error_of([&] { edited("<triangles count=\"12\">", "<triangles count=\"999999999\">"); }) ==
        "mesh:26: <triangles count=\"999999999\"> needs 2999999997 × 1 indices in its <p>, not 36");  // none made
  CHECK(error_of([&] { edited("1 2 6 1 6 5", "1 2 6 1 6 8"); }) == "mesh:26: <p> index 8 names no position (the mesh has 8)");
  CHECK(error_of([&] { edited("count=\"8\" stride", "count=\"9\" stride"); }) ==
        "mesh:16: <accessor count=\"9\"> reaches past its <float_array> of 24");
  CHECK(error_of([&] { edited("url=\"#cube\"", "url=\"#box\""); }) == "mesh:34: <instance_geometry url> names no <geometry>");
  CHECK(error_of([&] { edited("</COLLADA>", ""); }).find("mesh:") == 0);  // not XML: libxml2's words
  // What is left out changes nothing: a normal input at offset 1 (every
  // second index in <p>), a material, a polylist of quads for the triangles.
  const auto with_p = [](std::string s, const std::string& p) {
    const std::size_t at = s.find("<p>");
    return s.replace(at, s.find("</p>") - at, "<p>" + p);
  };
  std::string p;
  std::istringstream cube_p("0 2 1 0 3 2 4 5 6 4 6 7 0 1 5 0 5 4 1 2 6 1 6 5 2 3 7 2 7 6 3 0 4 3 4 7");
  for (std::string i; cube_p >> i;) p += i + " 0 ";
  std::string rich = with_p(dae, p);
  const std::string vertex_input = "<input semantic=\"VERTEX\" source=\"#cube-vertices\" offset=\"0\"/>";
  rich.replace(rich.find(vertex_input), vertex_input.size(),
               vertex_input + "<input semantic=\"NORMAL\" source=\"#cube-positions\" offset=\"1\"/>");
  rich.replace(rich.find("</asset>"), 8, "</asset><library_materials><material id=\"m\"/></library_materials>");
  const TriangleMesh same = parse_mesh(rich, "dae");
  CHECK(same == cube);
  std::string quads = dae;
  quads.replace(quads.find("<triangles count=\"12\">"), 22, "<polylist count=\"6\"><vcount>4 4 4 4 4 4</vcount>");
  quads.replace(quads.find("</triangles>"), 12, "</polylist>");
  CHECK(parse_mesh(with_p(quads, "0 3 2 1 4 5 6 7 0 1 5 4 1 2 6 5 2 3 7 6 3 0 4 7"), "dae").triangle_count() == 12);
  CHECK(error_of([] { read_mesh_file(kData + "no_such.stl"); }).find("cannot open") != std::string::npos);
}

// assimp's triangles of a COLLADA text read as it is, in world coordinates
// (the node transforms applied), sorted: what the rewrite must keep.
std::vector<std::array<float, 9>> assimp_triangles(const std::string& text) {
  std::vector<std::array<float, 9>> out;
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFileFromMemory(text.data(), text.size(), aiProcess_Triangulate, "dae");
  REQUIRE(scene);
  const std::function<void(const aiNode&, const aiMatrix4x4&)> walk = [&](const aiNode& node, const aiMatrix4x4& parent) {
    const aiMatrix4x4 T = parent * node.mTransformation;
    for (unsigned k = 0; k < node.mNumMeshes; ++k) {
      const aiMesh& m = *scene->mMeshes[node.mMeshes[k]];
      for (unsigned f = 0; f < m.mNumFaces; ++f) {
        std::array<float, 9> t{};
        for (unsigned i = 0; i < 3; ++i) {
          const aiVector3D p = T * m.mVertices[m.mFaces[f].mIndices[i]];
          t[3 * i] = p.x, t[3 * i + 1] = p.y, t[3 * i + 2] = p.z;
        }
        out.push_back(t);
      }
    }
    for (unsigned c = 0; c < node.mNumChildren; ++c) walk(*node.mChildren[c], T);
  };
  walk(*scene->mRootNode, aiMatrix4x4());
  std::sort(out.begin(), out.end());
  return out;
}

TEST_CASE("the COLLADA rewrite keeps what assimp reads from the file itself", "[sim]") {
  // cube.dae made like an exporter's (Blender's, MeshLab's): a polylist of
  // quads with a normal input, a material, inches and Z up, and nested nodes
  // with every transform kind (the same held for two real exports, MeshLab's
  // and Blender 2.78's, with and without such edits; not kept here).
  std::string text = slurp(kData + "cube.dae");
  const auto swap = [&text](const std::string& from, const std::string& to) { text.replace(text.find(from), from.size(), to); };
  swap("<triangles count=\"12\">", "<polylist count=\"6\" material=\"m\"><vcount>4 4 4 4 4 4</vcount>");
  swap("<input semantic=\"VERTEX\" source=\"#cube-vertices\" offset=\"0\"/>",
       "<input semantic=\"VERTEX\" source=\"#cube-vertices\" offset=\"0\"/><input semantic=\"NORMAL\" source=\"#cube-positions\" offset=\"1\"/>");
  const std::size_t p = text.find("<p>");
  text.replace(p, text.find("</p>") - p, "<p>0 0 3 1 2 2 1 3 4 4 5 5 6 6 7 7 0 0 1 1 5 5 4 4 1 1 2 2 6 6 5 5 2 2 3 3 7 7 6 6 3 3 0 0 4 4 7 7");
  swap("</triangles>", "</polylist>");
  swap("meter=\"0.01\"", "meter=\"0.0254\"");
  swap("Y_UP", "Z_UP");
  swap("</asset>", "</asset><library_materials><material id=\"m\"/></library_materials>");
  swap("<node id=\"cube-node\" name=\"cube\">",
       "<node id=\"outer\"><translate>1 2 3</translate><rotate>0 0 1 30</rotate><scale>1 2 0.5</scale>"
       "<instance_geometry url=\"#cube\"/><node id=\"cube-node\" name=\"cube\"><matrix>0.8 -0.6 0 0.5 0.6 0.8 0 -1 0 0 1 2 0 0 0 1</matrix>");
  swap("</node>", "</node></node>");
  const std::vector<std::array<float, 9>> expected = assimp_triangles(text);
  REQUIRE(expected.size() == 24);  // the cube twice, its quads split
  const TriangleMesh mesh = parse_mesh(text, "dae");
  std::vector<std::array<float, 9>> ours;
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3) {
    std::array<float, 9> tri{};
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) tri[3 * i + k] = mesh.vertices_m[3 * mesh.triangles[t + i] + k];
    ours.push_back(tri);
  }
  std::sort(ours.begin(), ours.end());
  CHECK(ours == expected);
}

TEST_CASE("urdf_tree robot files refuse what the tree cannot build, naming file, line and key", "[sim]") {
  const std::string yaml = slurp(kData + "pan_tilt.yaml");
  const std::string urdf = slurp(kData + "pan_tilt.urdf");
  TempRobot tmp("errors");
  const auto error = [&](const std::string& y, const std::string& u) {
    const std::string path = tmp.write(y, u);
    return error_of([&] { load_robot_description(path); });
  };
  CHECK(error(yaml, urdf) == "no error");
  CHECK(error(replaced(yaml, "    spin:", "    spun:"), urdf).find(":12: control.joints.spun: no joint 'spun' in the URDF") !=
        std::string::npos);
  CHECK(error(replaced(yaml, "    spin:", "    tip_joint:"), urdf).find("control.joints.tip_joint: joint 'tip_joint' is fixed") !=
        std::string::npos);
  CHECK(error(replaced(yaml, "mode: position", "mode: torque"), urdf).find("control.joints.pan.mode: expected position") !=
        std::string::npos);
  CHECK(error(replaced(yaml, "spin:  {mode: effort", "spin:  {mode: position"), urdf)
            .find("a continuous joint has no position limits") != std::string::npos);
  CHECK(error(yaml + "wheels: {}\n", urdf).find("wheels: a urdf_tree robot takes its body from the URDF") !=
        std::string::npos);
  CHECK(error(yaml, replaced(urdf, "filename=\"cube.dae", "filename=\"package://rig/cube.dae")).find("package:// needs a ROS package path") !=
        std::string::npos);
  CHECK(error(yaml, replaced(urdf, "filename=\"cube.dae", "filename=\"missing.stl")).find("missing.stl: cannot open") != std::string::npos);
  CHECK(error(yaml, replaced(urdf, "<mass value=\"0.2\"/>", "<mass value=\"0\"/>")).find("mass must be > 0") !=
        std::string::npos);
  CHECK(error(yaml, replaced(urdf, "izz=\"1.6e-4\"", "izz=\"1.0\"")).find("inertia is not a rigid body's") !=
        std::string::npos);
  CHECK(error(yaml, replaced(urdf, "lower=\"-0.5\" upper=\"0.8\"", "lower=\"0.8\" upper=\"-0.5\""))
            .find("joint 'tilt': limit lower must be <= upper") != std::string::npos);
  CHECK(error(yaml, replaced(urdf, "<axis xyz=\"0 1 0\"/>", "<axis xyz=\"0 0 0\"/>"))
            .find("joint 'tilt': axis must be a finite, non-zero vector") != std::string::npos);
}

TEST_CASE("the existing robots still parse as their fixed models", "[sim]") {
  CHECK(load_robot_description(kRobots + "skid4.yaml").kind == RobotKind::SkidSteer);
  CHECK_FALSE(load_robot_description(kRobots + "tracked_eod.yaml").tree);
}
