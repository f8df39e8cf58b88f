#include <catch2/catch.hpp>

#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "semantic/world_export.hpp"
#include "sim/simulation.hpp"
#include "sim/world_description.hpp"
#include "tests/semantic/building_cloud.hpp"
#include "tests/semantic/ground_truth.hpp"

using namespace rise::semantic;
using namespace rise::semantic::testing;

namespace {
constexpr double kDeg = M_PI / 180.0;

std::filesystem::path temp_file(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("rise_world_export_test_" + name);
}

const SemanticNet& building_net() {
  static const SemanticNet net(building_segmentation());
  return net;
}
}  // namespace

TEST_CASE("the exported world file loads in rise::sim and matches the building's walls, doors and stairs", "[semantic]") {
  const auto original = rise::sim::load_world_description(kBuilding);
  ExportSettings st;
  st.world_name = "building_found";
  const auto path = temp_file("world.yaml");
  write_text_file(path.string(), world_yaml(building_net(), st));
  const auto world = rise::sim::load_world_description(path.string());
  CHECK(world.name == "building_found");

  const WallScore walls = score_walls(original.walls, std::vector<Wall>(building_net().segmentation().walls));
  INFO(walls.report);
  // The walls as the simulator read them back, against the original's.
  std::vector<Wall> loaded;
  for (const auto& w : world.walls) {
    Wall x;
    x.from_m = v2(w.from_m);
    x.to_m = v2(w.to_m);
    loaded.push_back(x);
    CHECK(w.height_m == Approx(2.5).margin(0.03));
  }
  const WallScore s = score_walls(original.walls, loaded);
  INFO(s.report);
  CHECK(s.precision() >= 0.95);
  CHECK(s.recall() >= 0.95);

  const auto truth = truth_doors(original), found = truth_doors(world);
  REQUIRE(found.size() == truth.size());
  for (const auto& t : truth) {
    const TruthDoor* best = nullptr;
    for (const auto& f : found)
      if (!best || (f.center - t.center).norm() < (best->center - t.center).norm()) best = &f;
    INFO(t.name << " found as " << best->name);
    CHECK((best->center - t.center).norm() < 0.10);
    CHECK(best->width_m == Approx(t.width_m).margin(0.10));
    CHECK(best->height_m == Approx(t.height_m).margin(0.10));
  }
  REQUIRE(world.doors.size() == 1);  // the closed one; the doorway has none
  CHECK(world.doors[0].width_m == Approx(original.doors[0].width_m).margin(0.10));

  REQUIRE(world.stairs.size() == 1);
  const auto &a = world.stairs[0], &b = original.stairs[0];
  CHECK(a.steps == b.steps);
  CHECK(a.riser_m == Approx(b.riser_m).margin(0.01));
  CHECK(a.tread_m == Approx(b.tread_m).margin(0.01));
  CHECK(std::abs(std::remainder(a.yaw_rad - b.yaw_rad, 2 * M_PI)) < 2 * kDeg);
  CHECK((v2(a.start_m) - v2(b.start_m)).norm() < 0.05);
  REQUIRE(world.ceiling.has_value());
  CHECK(world.ceiling->height_m == Approx(2.6).margin(0.02));
  CHECK(world.props.size() == building_net().segmentation().obstacles.size());

  // The simulator builds it, and its robot starts in free space: rays from
  // the start reach at least 0.5 m in every direction.
  rise::sim::Simulation sim(rise::sim::load_robot_description(kTracked), world);
  const Eigen::Vector3d origin(world.robot_start_m[0], world.robot_start_m[1], 0.5);
  for (int k = 0; k < 16; ++k) {
    const Eigen::Vector3d dir(std::cos(k * M_PI / 8), std::sin(k * M_PI / 8), 0.0);
    CHECK(sim.cast_ray_m(origin + dir * 0.6, dir, 30.0) > 0.5);
  }
  std::filesystem::remove(path);
}

TEST_CASE("a found wall's opening survives the world file round trip", "[semantic]") {
  const auto path = temp_file("round.yaml");
  write_text_file(path.string(), world_yaml(building_net()));
  const auto world = rise::sim::load_world_description(path.string());
  int openings = 0;
  for (const auto& w : world.walls) openings += static_cast<int>(w.openings.size());
  int found = 0;
  for (const auto& w : building_net().segmentation().walls) found += static_cast<int>(w.openings.size());
  CHECK(openings == found);
  CHECK(openings == 1);
  std::filesystem::remove(path);
}

TEST_CASE("the SDF world is well-formed XML with one static model per solid", "[semantic]") {
  const auto path = temp_file("world.sdf");
  write_text_file(path.string(), sdf_world(building_net()));
  std::size_t solids = 0;
  for (const auto& b : model_boxes(building_net()))
    if (b.kind != "floor") ++solids;
  const std::string cmd =
      "/usr/bin/python3 -c \"import sys, xml.etree.ElementTree as E; r=E.parse(sys.argv[1]).getroot(); "
      "assert r.tag=='sdf' and r.get('version')=='1.6'; w=r.find('world'); m=w.findall('model'); "
      "assert len(m)==int(sys.argv[2])+1, len(m); "
      "assert all(x.find('static').text=='true' for x in m); "
      "assert all(len(x.find('link/collision/geometry/box/size').text.split())==3 for x in m[1:]); "
      "assert len(set(x.get('name') for x in m))==len(m)\" " +
      path.string() + " " + std::to_string(solids);
  CHECK(std::system(cmd.c_str()) == 0);
  std::filesystem::remove(path);
}

TEST_CASE("the OBJ mesh has eight vertices and six faces per solid", "[semantic]") {
  const auto boxes = model_boxes(building_net());
  std::istringstream in(obj_mesh(building_net()));
  std::string line;
  std::size_t v = 0, f = 0, o = 0;
  bool indices_ok = true;
  while (std::getline(in, line)) {
    if (line.rfind("v ", 0) == 0) ++v;
    if (line.rfind("o ", 0) == 0) ++o;
    if (line.rfind("f ", 0) == 0) {
      ++f;
      std::istringstream fs(line.substr(2));
      std::size_t i;
      while (fs >> i) indices_ok = indices_ok && i >= 1 && i <= v;
    }
  }
  CHECK(o == boxes.size());
  CHECK(v == 8 * boxes.size());
  CHECK(f == 6 * boxes.size());
  CHECK(indices_ok);
}

TEST_CASE("the PNG map shows walls in black, doors in green and stairs in blue where they are", "[semantic]") {
  const auto path = temp_file("map.png");
  ExportSettings st;
  st.map_px_per_m = 50;
  write_map_png(path.string(), building_net(), &building_cloud(), st);
  const cv::Mat img = cv::imread(path.string(), cv::IMREAD_COLOR);
  REQUIRE(!img.empty());
  // The map spans the floor's extent (-4..9 x -3..5.5 m and their walls) plus 0.5 m margins.
  CHECK(img.cols == Approx(50 * 14.2).margin(15));
  CHECK(img.rows == Approx(50 * 9.7).margin(15));
  const auto& seg = building_net().segmentation();
  Eigen::Vector2d lo = seg.floor.min_m, hi = seg.floor.max_m;
  for (const auto& b : model_boxes(building_net()))
    for (double sx : {-0.5, 0.5})
      for (double sy : {-0.5, 0.5}) {
        const double c = std::cos(b.yaw_rad), s = std::sin(b.yaw_rad);
        const Eigen::Vector2d p = b.center_m.head<2>() + Eigen::Vector2d(c * sx * b.size_m.x() - s * sy * b.size_m.y(),
                                                                         s * sx * b.size_m.x() + c * sy * b.size_m.y());
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
  const auto at = [&](double x, double y) {
    return img.at<cv::Vec3b>(static_cast<int>((hi.y() + 0.5 - y) * 50), static_cast<int>((x - lo.x() + 0.5) * 50));
  };
  CHECK(at(-4.0, -1.0)[1] < 60);                                  // the west wall: black
  const cv::Vec3b door = at(3.0, -0.2);
  CHECK((door[1] > 120 && door[0] < 100 && door[2] < 100));       // door_ab: green
  const cv::Vec3b stairs = at(1.2, 4.0);
  CHECK((stairs[0] > 180 && stairs[2] < 140));                    // the staircase: blue
  std::filesystem::remove(path);
}

TEST_CASE("writing an export where it cannot be written fails with the path", "[semantic]") {
  CHECK_THROWS_WITH(write_text_file("/nonexistent/dir/world.yaml", "x"), Catch::Contains("/nonexistent/dir/world.yaml"));
}
