#include <catch2/catch.hpp>

#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <sys/wait.h>

#include "sim/world_description.hpp"
#include "tests/semantic/building_cloud.hpp"
#include "tests/test_data.hpp"

using namespace rise::semantic::testing;

namespace {
const std::string kProgram = std::string(RISE_BINARY_DIR) + "/bin/rise-semantic";

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The building's cloud as a binary PCD file, written once.
std::filesystem::path building_pcd() {
  static const std::filesystem::path path = [] {
    const auto p = std::filesystem::temp_directory_path() / "rise_segment_command_test_building.pcd";
    pcl::PointCloud<pcl::PointXYZ> pc;
    for (const auto& q : building_cloud().points) pc.points.emplace_back(q.x(), q.y(), q.z());
    pc.width = static_cast<uint32_t>(pc.points.size());
    pc.height = 1;
    pcl::io::savePCDFileBinary(p.string(), pc);
    return p;
  }();
  return path;
}
}  // namespace

TEST_CASE("rise-semantic segment prints the building's entities as JSON and writes a world rise::sim loads", "[semantic]") {
  const auto dir = std::filesystem::temp_directory_path() / "rise_segment_command_test_out";
  std::filesystem::remove_all(dir);
  const auto json = dir.string() + ".json";
  const std::string cmd = kProgram + " segment " + building_pcd().string() + " --json --name found -o " + dir.string() + " > " + json;
  REQUIRE(std::system(cmd.c_str()) == 0);
  const std::string check = "/usr/bin/python3 -c \"import json,sys; d=json.load(open(sys.argv[1])); "
                            "s=[e for e in d['entities'] if e['kind']=='stairs']; "
                            "assert len(s)==1 and s[0]['steps']==6 and abs(s[0]['riser_m']-0.17)<0.01, s; "
                            "assert sum(e['kind']=='door' for e in d['entities'])==2; "
                            "assert all(len(e['position_m'])==3 and len(e['size_m'])==3 for e in d['entities'])\" " + json;
  CHECK(std::system(check.c_str()) == 0);
  for (const char* f : {"world.yaml", "world.sdf", "model.obj", "map.png"}) {
    INFO(f);
    CHECK(std::filesystem::file_size(dir / f) > 100);
  }
  const auto world = rise::sim::load_world_description((dir / "world.yaml").string());
  CHECK(world.name == "found");
  CHECK(world.stairs.size() == 1);
  // 8: the east wall is one wall past the T of the corridor wall meeting it
  // (its face's gap there, with no floor seen through it, is closed).
  CHECK(world.walls.size() >= 8);
  std::filesystem::remove_all(dir);
  std::filesystem::remove(json);
}

TEST_CASE("rise-semantic segment refuses a missing cloud with its name and exit code 2", "[semantic]") {
  const auto err = std::filesystem::temp_directory_path() / "rise_segment_command_test.err";
  const std::string cmd = kProgram + " segment /nonexistent/cloud.pcd 2> " + err.string();
  const int rc = std::system(cmd.c_str());
  REQUIRE(WIFEXITED(rc));
  CHECK(WEXITSTATUS(rc) == 2);
  CHECK(slurp(err).find("/nonexistent/cloud.pcd") != std::string::npos);
  std::filesystem::remove(err);
}

TEST_CASE("rise-semantic segment writes the map and refuses a start with no room, exit code 1", "[semantic]") {
  // A 4 x 4 m floor with a 0.5 m post every 0.5 m: nowhere 0.6 m from everything.
  const auto cloud = std::filesystem::temp_directory_path() / "rise_segment_command_test_posts.pcd";
  pcl::PointCloud<pcl::PointXYZ> pc;
  for (double x = -2; x <= 2; x += 0.02)
    for (double y = -2; y <= 2; y += 0.02) {
      const bool post = std::abs(x - 0.5 * std::round(x / 0.5)) < 0.03 && std::abs(y - 0.5 * std::round(y / 0.5)) < 0.03;
      for (double z = 0; z <= (post ? 0.5 : 0.0); z += 0.02)
        pc.points.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
    }
  pc.width = static_cast<uint32_t>(pc.points.size());
  pc.height = 1;
  pcl::io::savePCDFileBinary(cloud.string(), pc);
  const auto dir = std::filesystem::temp_directory_path() / "rise_segment_command_test_posts";
  const auto err = std::filesystem::temp_directory_path() / "rise_segment_command_test_posts.err";
  std::filesystem::remove_all(dir);
  const std::string cmd = kProgram + " segment " + cloud.string() + " -o " + dir.string() + " > /dev/null 2> " + err.string();
  const int status = std::system(cmd.c_str());
  INFO(slurp(err));
  CHECK(WEXITSTATUS(status) == 1);
  CHECK(slurp(err).find("no free place on the floor plan with 0.60 m clearance") != std::string::npos);
  CHECK(std::filesystem::exists(dir / "map.png"));
  CHECK_FALSE(std::filesystem::exists(dir / "world.yaml"));
  std::filesystem::remove_all(dir);
  std::filesystem::remove(err);
  std::filesystem::remove(cloud);
}

TEST_CASE("rise-semantic segment on PCL's room scan finds room for the robot on the floor seen east of the furniture",
          "[semantic]") {
  const std::string file = rise::test::data_file("pointclouds/PointCloudLibrary_data/room_scan1.pcd");
  if (file.empty()) {
    WARN("skipped: RISE_TEST_DATA/pointclouds/PointCloudLibrary_data/room_scan1.pcd is absent");
    return;
  }
  // The floor's noise reaches 6.6 cm (Floor::noise_m): with occupied from
  // a fixed 5 cm up, it speckled the free floor and no place had room.
  const auto dir = std::filesystem::temp_directory_path() / "rise_segment_command_test_room";
  std::filesystem::remove_all(dir);
  const std::string cmd = kProgram + " segment " + file + " -o " + dir.string() + " > /dev/null 2>&1";
  REQUIRE(std::system(cmd.c_str()) == 0);
  const auto world = rise::sim::load_world_description((dir / "world.yaml").string());
  CHECK(world.robot_start_m[0] == Approx(3.16).margin(0.3));
  CHECK(world.robot_start_m[1] == Approx(0.36).margin(0.3));
  std::filesystem::remove_all(dir);
}
