#include <catch2/catch.hpp>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "sim/laser_scanner.hpp"
#include "sim/pcd_file.hpp"
#include "sim/simulation.hpp"

using namespace rise::sim;
namespace fs = std::filesystem;

namespace {
const std::string kTracked = std::string(RISE_SOURCE_DIR) + "/sim/robots/tracked_eod.yaml";
const std::string kBuilding = std::string(RISE_SOURCE_DIR) + "/sim/worlds/building.yaml";

// A fresh folder for this process's files.
fs::path temp_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("rise_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string write_text(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
  return path.string();
}

std::string read_error(const std::string& path) {
  try {
    read_pcd(path);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}
}  // namespace

TEST_CASE("a scan's PCD and pose files read back to the same points and viewpoint", "[sim]") {
  const PcdFormat format = GENERATE(PcdFormat::Ascii, PcdFormat::Binary);
  Simulation sim(load_robot_description(kTracked), load_world_description(kBuilding));
  for (int i = 0; i < 300; ++i) sim.step();
  LaserScanner scanner(*sim.robot().sensors.laser, 3);
  const LaserScan scan = scanner.scan(sim);
  REQUIRE(scan.points_sensor.size() > 40000);
  const fs::path dir = temp_dir("pcd_round_trip");
  const std::string stem = (dir / "scan_0000").string();
  write_scan(stem, scan, format);

  const PointCloud cloud = read_pcd(stem + ".pcd");
  CHECK(cloud.width == scan.points_sensor.size());
  CHECK(cloud.height == 1);
  REQUIRE(cloud.points.size() == scan.points_sensor.size());
  CHECK(std::memcmp(cloud.points.data(), scan.points_sensor.data(), cloud.points.size() * sizeof(Eigen::Vector3f)) == 0);
  // The viewpoint is written as the shortest exact text of each double.
  CHECK((cloud.viewpoint.translation() - scan.T_world_sensor.translation()).norm() < 1e-12);
  CHECK((cloud.viewpoint.linear() - scan.T_world_sensor.linear()).norm() < 1e-12);
  // The PCD's points through its VIEWPOINT are the scan's world points.
  CHECK((cloud.viewpoint * cloud.points[123].cast<double>() - scan.points_world[123].cast<double>()).norm() < 1e-4);

  const PoseFile pose = read_pose(stem + ".pose");
  CHECK(pose.time_s == Approx(0.3).margin(1e-12));
  CHECK((pose.T_world_sensor.matrix() - scan.T_world_sensor.matrix()).norm() < 1e-12);
  fs::remove_all(dir);
}

TEST_CASE("the PCD header is PCL's v0.7 layout", "[sim]") {
  const fs::path dir = temp_dir("pcd_header");
  const std::vector<Eigen::Vector3f> points = {{1.0f, 2.0f, 3.0f}, {-0.5f, 0.25f, 1e-3f}};
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translate(Eigen::Vector3d(1.5, -2.0, 0.32));
  write_pcd((dir / "a.pcd").string(), points, T, PcdFormat::Ascii);
  std::ifstream in(dir / "a.pcd");
  std::stringstream text;
  text << in.rdbuf();
  CHECK(text.str() ==
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
        "WIDTH 2\nHEIGHT 1\nVIEWPOINT 1.5 -2 0.32 1 0 0 0\nPOINTS 2\nDATA ascii\n1 2 3\n-0.5 0.25 0.001\n");
  write_pcd((dir / "b.pcd").string(), points, T, PcdFormat::Binary);
  CHECK(fs::file_size(dir / "b.pcd") == text.str().size() - std::string("ascii\n1 2 3\n-0.5 0.25 0.001\n").size() +
                                            std::string("binary\n").size() + 2 * 12);
  fs::remove_all(dir);
}

TEST_CASE("the PCD reader takes other fields and refuses what it cannot read with file:line", "[sim]") {
  const fs::path dir = temp_dir("pcd_reader");
  const std::string header = "VERSION .7\nFIELDS intensity x y z\nSIZE 2 4 4 4\nTYPE U F F F\nCOUNT 1 1 1 1\n"
                             "WIDTH 2\nHEIGHT 1\nPOINTS 2\n";
  SECTION("ascii with an extra field, no VIEWPOINT") {
    const auto cloud = read_pcd(write_text(dir / "i.pcd", header + "DATA ascii\n7 1 2 3\n8 4 5 nan\n"));
    REQUIRE(cloud.points.size() == 2);
    CHECK(cloud.points[1].x() == 4.0f);
    CHECK(std::isnan(cloud.points[1].z()));
    CHECK(cloud.viewpoint.matrix() == Eigen::Matrix4d::Identity());
  }
  SECTION("binary with an extra field") {
    std::string data = header + "DATA binary\n";
    const float xyz[2][3] = {{1, 2, 3}, {4, 5, 6}};
    for (const auto& p : xyz) {
      data.append(2, '\0');
      data.append(reinterpret_cast<const char*>(p), sizeof p);
    }
    const auto cloud = read_pcd(write_text(dir / "b.pcd", data));
    REQUIRE(cloud.points.size() == 2);
    CHECK(cloud.points[1] == Eigen::Vector3f(4, 5, 6));
  }
  SECTION("bad input") {
    CHECK(read_error(write_text(dir / "c.pcd", header + "DATA binary_compressed\n")) ==
          (dir / "c.pcd").string() + ":9: DATA: expected ascii or binary (binary_compressed is not supported)");
    CHECK(read_error(write_text(dir / "t.pcd", header + "DATA binary\n1234")) ==
          (dir / "t.pcd").string() + ":9: DATA: shorter than POINTS × point size");
    CHECK(read_error(write_text(dir / "v.pcd", header + "DATA ascii\n7 1 2 3\n8 4 five 6\n")) ==
          (dir / "v.pcd").string() + ":11: DATA: cannot read 'five'");
    CHECK(read_error(write_text(dir / "w.pcd", "VERSION 0.7\nFIELDS x y\nSIZE 4 4\nTYPE F F\nWIDTH 0\nDATA ascii\n")) ==
          (dir / "w.pcd").string() + ":6: FIELDS: needs x, y and z");
    CHECK(read_error((dir / "missing.pcd").string()) ==
          (dir / "missing.pcd").string() + ": cannot open: No such file or directory");
  }
  fs::remove_all(dir);
}

TEST_CASE("rise-sim --scan-dir writes a scan at start and every --scan-every seconds of sim time", "[sim]") {
  const fs::path dir = temp_dir("rise_sim_scans");
  // memq:// keeps the run off the network; --fast --duration ends it by itself.
  const std::string command = "timeout 120 " + std::string(RISE_BINARY_DIR) + "/bin/rise-sim --robot " +
                              std::string(RISE_SOURCE_DIR) + "/sim/robots/tracked_eod.yaml --world " + kBuilding +
                              " --lcm memq:// --fast --duration 2.5 --log-level warn --scan-format ascii --scan-every 1"
                              " --scan-dir " + dir.string();
  REQUIRE(std::system(command.c_str()) == 0);
  for (int k = 0; k < 3; ++k) {
    const std::string stem = (dir / ("scan_000" + std::to_string(k))).string();
    INFO(stem);
    const PoseFile pose = read_pose(stem + ".pose");
    CHECK(pose.time_s == Approx(k).margin(1e-9));
    const PointCloud cloud = read_pcd(stem + ".pcd");
    CHECK(cloud.points.size() > 40000);
    CHECK((cloud.viewpoint.matrix() - pose.T_world_sensor.matrix()).norm() < 1e-12);
    // The robot stands at the start: the sensor 25 cm ahead of the chassis centre.
    CHECK(pose.T_world_sensor.translation().x() == Approx(0.25).margin(0.005));
  }
  CHECK_FALSE(fs::exists(dir / "scan_0003.pcd"));
  fs::remove_all(dir);
}
