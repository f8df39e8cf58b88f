// `rise-semantic map` end to end: the simulator's laser scans the example
// building from a known path (room A, through the doorway into the
// corridor, to the foot of the stairs); the scans are written as PCD +
// .pose with drifting odometry as the pose guess; the built program maps
// them; the recovered poses are checked against the truth, and the tracked
// robot drives through the door and up the stairs of the world it wrote.

#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "semantic/cloud_io.hpp"
#include "sim/pcd_file.hpp"
#include "sim/simulation.hpp"
#include "sim/world_description.hpp"
#include "tests/semantic/ground_truth.hpp"
#include "tests/semantic/scan_sequence.hpp"
#include "tests/semantic/sim_drive.hpp"
#include "tests/semantic/synthetic_room.hpp"

using namespace rise::semantic;
using namespace rise::semantic::testing;
namespace fs = std::filesystem;

namespace {
const std::string kProgram = std::string(RISE_BINARY_DIR) + "/bin/rise-semantic";
constexpr double kDeg = M_PI / 180.0;

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The robot's stops (x, y, yaw): room A facing the closed door to room B,
// across room A, through the open doorway into the corridor and on to the
// foot of the staircase, looking up it.
const std::vector<Eigen::Vector3d>& stops() {
  static const std::vector<Eigen::Vector3d> s = {
      {0.0, 0.0, 0.0},           {-1.2, -1.6, 40.0 * kDeg},  {-2.3, 0.2, 80.0 * kDeg},  {-2.25, 1.9, 90.0 * kDeg},
      {-2.3, 3.6, 60.0 * kDeg},  {-2.6, 4.4, 0.0},           {-1.2, 4.2, -10.0 * kDeg}, {-0.5, 3.5, 20.0 * kDeg}};
  return s;
}

// The scans of stops() written to `dir` as scanNN.pcd (binary, sensor frame)
// + scanNN.pose (the drifting odometry's pose, not the truth); the truth.
struct WrittenScans {
  std::vector<std::string> files;
  std::vector<Eigen::Isometry3d> truth;
  std::vector<Eigen::Isometry3d> odometry;
  std::size_t points = 0;
};

WrittenScans write_scans(const fs::path& dir) {
  const LaserScans s = laser_scans(stops(), 21, 1.0 * kDeg, 120);
  WrittenScans out;
  out.truth = s.T_world_sensor;
  out.odometry = drifting_odometry(s.T_world_sensor, s.T_base_sensor);
  for (std::size_t i = 0; i < s.clouds.size(); ++i) {
    char stem[32];
    std::snprintf(stem, sizeof stem, "scan%02zu", i);
    const std::string pcd = (dir / (std::string(stem) + ".pcd")).string();
    rise::sim::write_pcd(pcd, s.clouds[i].points, out.odometry[i], rise::sim::PcdFormat::Binary);
    rise::sim::write_pose((dir / (std::string(stem) + ".pose")).string(), out.odometry[i], 0.0);
    out.files.push_back(pcd);
    out.points += s.clouds[i].size();
  }
  return out;
}

// poses.txt: "name x y z qw qx qy qz" per line after '#' comments.
std::map<std::string, Eigen::Isometry3d> read_poses(const fs::path& p) {
  std::map<std::string, Eigen::Isometry3d> out;
  std::istringstream in(slurp(p));
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream l(line);
    std::string name;
    double x, y, z, qw, qx, qy, qz;
    REQUIRE(static_cast<bool>(l >> name >> x >> y >> z >> qw >> qx >> qy >> qz));
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
    T.translation() = Eigen::Vector3d(x, y, z);
    out[name] = T;
  }
  return out;
}

struct RemovedAtExit {
  fs::path dir;
  ~RemovedAtExit() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
};

// The scans written, mapped by the program once per test program.
struct Mapped {
  WrittenScans scans;
  int rc = -1;
  std::string printed, log;
  fs::path out_dir;
};

const Mapped& mapped() {
  static const Mapped m = [] {
    Mapped m;
    // ctest runs each test case in its own process, maybe at once: a folder per process.
    const fs::path dir = fs::temp_directory_path() / ("rise_map_command_test_" + std::to_string(getpid()));
    const fs::path scans_dir = dir / "scans";
    m.out_dir = dir / "out";
    fs::remove_all(dir);
    static const RemovedAtExit cleanup{dir};
    fs::create_directories(scans_dir);
    m.scans = write_scans(scans_dir);
    std::string cmd = kProgram + " map";
    for (const auto& f : m.scans.files) cmd += " " + f;
    // One ICP thread: on a busy machine OpenMP's spinning threads slow the match down many times.
    cmd += " --threads 1 -o " + m.out_dir.string() + " > " + (dir / "stdout.txt").string() + " 2> " +
           (dir / "stderr.txt").string();
    m.rc = std::system(cmd.c_str());
    m.printed = slurp(dir / "stdout.txt");
    m.log = slurp(dir / "stderr.txt");
    return m;
  }();
  return m;
}

// The generated world, loaded by the simulator's own reader.
rise::sim::WorldDescription generated_world() {
  const Mapped& m = mapped();
  INFO(m.printed << m.log);
  REQUIRE(WIFEXITED(m.rc));
  REQUIRE(WEXITSTATUS(m.rc) == 0);
  return rise::sim::load_world_description((m.out_dir / "world.yaml").string());
}

}  // namespace

TEST_CASE("rise-semantic map recovers the poses of drifting simulated scans within 2 cm and 0.5 deg", "[semantic]") {
  const Mapped& m = mapped();
  const Errors guess = errors(m.scans.odometry, m.scans.truth);
  INFO(m.scans.points << " points in " << m.scans.files.size() << " scans; odometry off by up to " << guess.max_t_m
                      << " m, " << guess.max_r_rad / kDeg << " deg");
  INFO(m.printed << m.log);
  REQUIRE(guess.max_t_m > 0.3);
  REQUIRE(WIFEXITED(m.rc));
  REQUIRE(WEXITSTATUS(m.rc) == 0);
  for (const char* f : {"world.yaml", "map.png", "world.sdf", "mesh.obj", "map.pcd", "poses.txt", "entities.json"})
    CHECK(fs::file_size(m.out_dir / f) > 100);
  CHECK(m.printed.find("8 scans") != std::string::npos);
  CHECK(m.printed.find("timings: read") != std::string::npos);
  CHECK(m.log.find("sequential icp: 7/7") != std::string::npos);  // the progress bar, one line per stage off a terminal
  const auto world = rise::sim::load_world_description((m.out_dir / "world.yaml").string());
  CHECK(m.printed.find(std::to_string(world.walls.size()) + " walls, ") != std::string::npos);
  CHECK(m.printed.find(std::to_string(world.stairs.size()) + " stairs, ") != std::string::npos);

  const auto poses = read_poses(m.out_dir / "poses.txt");
  REQUIRE(poses.size() == m.scans.truth.size());
  std::vector<Eigen::Isometry3d> got;
  for (std::size_t i = 0; i < m.scans.truth.size(); ++i) {
    char stem[32];
    std::snprintf(stem, sizeof stem, "scan%02zu", i);
    REQUIRE(poses.count(stem) == 1);
    got.push_back(poses.at(stem));
  }
  const Errors e = errors(got, m.scans.truth);
  INFO("recovered poses: max " << e.max_t_m << " m, " << e.max_r_rad / kDeg << " deg, sum " << e.sum_t_m << " m");
  for (std::size_t i = 0; i < got.size(); ++i) {
    INFO("scan " << i);
    CHECK(translation_error_m(got[i], m.scans.truth[i]) < 0.02);
    CHECK(rotation_error_rad(got[i], m.scans.truth[i]) < 0.5 * kDeg);
  }
}

TEST_CASE("the tracked robot drives through the door rise-semantic map found", "[semantic]") {
  const auto world = generated_world();
  const auto found = doorways(world);
  INFO(mapped().printed);
  REQUIRE(!found.empty());
  // The door the scans saw from room A: its approach side is the one the
  // first scan stood on; 1.5 m before the gap's middle, facing it.
  const Eigen::Vector2d seen_from = mapped().scans.truth[0].translation().head<2>();
  const Doorway* door = &found.front();
  for (const auto& d : found)
    if ((d.center - seen_from).norm() < (door->center - seen_from).norm()) door = &d;
  const double side = door->normal.dot(seen_from - door->center) > 0 ? 1.0 : -1.0;
  const Eigen::Vector2d toward = -side * door->normal;  // from the approach side through the gap
  const Eigen::Vector2d start = door->center - 1.5 * toward;
  auto w = world;
  w.robot_start_m = {start.x(), start.y()};
  w.robot_start_yaw_rad = std::atan2(toward.y(), toward.x());
  rise::sim::Simulation sim(rise::sim::load_robot_description(kTracked), w);
  sim.set_input(drive(1.0f, 0));  // slow: push a hinged door open rather than break it
  std::vector<rise::sim::SimEvent> log;
  run(sim, 16.0, log);
  const auto p = sim.snapshot().position_m;
  const double past_m = toward.dot(Eigen::Vector2d(p[0], p[1]) - door->center);
  const double off_m = std::abs(door->along.dot(Eigen::Vector2d(p[0], p[1]) - door->center));
  INFO("door " << (door->door.empty() ? "opening" : door->door) << " at (" << door->center.x() << ", "
               << door->center.y() << ") width " << door->width_m << ": base " << past_m << " m past its wall line, "
               << off_m << " m off its middle");
  CHECK(past_m > 0.5);
  CHECK(off_m < door->width_m / 2);
  if (!door->door.empty()) CHECK(any(log, rise::sim::SimEventKind::DoorOpened, door->door));
  CHECK_FALSE(any(log, rise::sim::SimEventKind::TippedOver));
  CHECK_FALSE(any(log, rise::sim::SimEventKind::JointBroken));
}

TEST_CASE("the tracked robot climbs the stairs rise-semantic map found to their landing", "[semantic]") {
  const auto world = generated_world();
  INFO(mapped().printed);
  REQUIRE(world.stairs.size() == 1);
  const auto& st = world.stairs.front();
  const Eigen::Vector2d dir(std::cos(st.yaw_rad), std::sin(st.yaw_rad));
  const Eigen::Vector2d start = v2(st.start_m) - 1.5 * dir;  // 1.5 m before the first riser, facing it
  auto w = world;
  w.robot_start_m = {start.x(), start.y()};
  w.robot_start_yaw_rad = st.yaw_rad;
  rise::sim::Simulation sim(rise::sim::load_robot_description(kTracked), w);
  sim.set_input(drive(1.0f, 2));
  std::vector<rise::sim::SimEvent> log;
  run(sim, 10.0, log, rise::sim::SimEventKind::StairsClimbed, st.name, true);
  INFO("stairs " << st.name << ": " << st.steps << " steps, riser " << st.riser_m << ", tread " << st.tread_m
                 << ", landing " << st.landing_m << "; climbed at " << sim.time_s() << " s");
  CHECK(any(log, rise::sim::SimEventKind::StairsClimbed, st.name));
  CHECK(sim.snapshot().position_m[2] > st.landing_height_m());
  CHECK_FALSE(any(log, rise::sim::SimEventKind::TippedOver));
}

TEST_CASE("rise-semantic map refuses a missing scan and bad flags with exit code 2", "[semantic]") {
  const fs::path dir = fs::temp_directory_path() / ("rise_map_command_test_bad_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string err = (dir / "stderr.txt").string();
  SECTION("a missing scan is named") {
    const int rc = std::system((kProgram + " map /nonexistent/scan00.pcd -o " + (dir / "out").string() + " 2> " + err).c_str());
    REQUIRE(WIFEXITED(rc));
    CHECK(WEXITSTATUS(rc) == 2);
    CHECK(slurp(err).find("/nonexistent/scan00.pcd") != std::string::npos);
  }
  SECTION("a broken scan file is named") {
    { std::ofstream(dir / "bad.pcd") << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n1 2\n"; }
    const int rc = std::system((kProgram + " map " + (dir / "bad.pcd").string() + " -o " + (dir / "out").string() + " 2> " + err).c_str());
    REQUIRE(WIFEXITED(rc));
    CHECK(WEXITSTATUS(rc) == 2);
    CHECK(slurp(err).find("bad.pcd") != std::string::npos);
  }
  SECTION("an unknown ICP metric is named") {
    { std::ofstream(dir / "a.xyz") << "0 0 0\n1 0 0\n"; }
    const int rc = std::system((kProgram + " map " + (dir / "a.xyz").string() + " --metric plain -o " + (dir / "out").string() + " 2> " + err).c_str());
    REQUIRE(WIFEXITED(rc));
    CHECK(WEXITSTATUS(rc) == 2);
    CHECK(slurp(err).find("--metric") != std::string::npos);
  }
  fs::remove_all(dir);
}

TEST_CASE("rise-semantic map refuses a scan that did not register, with one line and exit code 1", "[semantic]") {
  const fs::path dir = fs::temp_directory_path() / ("rise_map_command_test_refused_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  // The same room twice, the second 30 m away with no pose to say so: the
  // second scan's match pairs nothing.
  const rise::semantic::Cloud room = rise::semantic::test::synthetic_room(20000, 1);
  rise::semantic::write_cloud((dir / "scan00.xyz").string(), room);
  rise::semantic::write_cloud((dir / "scan01.xyz").string(),
                              rise::semantic::transformed(room, Eigen::Isometry3d(Eigen::Translation3d(30, 0, 0))));
  const std::string err = (dir / "stderr.txt").string();
  const int rc = std::system((kProgram + " map " + (dir / "scan00.xyz").string() + " " + (dir / "scan01.xyz").string() +
                              " --threads 1 -o " + (dir / "out").string() + " > /dev/null 2> " + err)
                                 .c_str());
  REQUIRE(WIFEXITED(rc));
  CHECK(WEXITSTATUS(rc) == 1);
  const std::string log = slurp(err);
  INFO(log);
  CHECK(log.find("scan01 (too few pairs") != std::string::npos);
  CHECK(log.find("no map written") != std::string::npos);
  CHECK_FALSE(fs::exists(dir / "out" / "world.yaml"));
  fs::remove_all(dir);
}
