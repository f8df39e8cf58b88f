#include <catch2/catch.hpp>

#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
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

namespace {
// Metres from p to a box's footprint (0 inside).
double footprint_distance(const ModelBox& b, const Eigen::Vector2d& p) {
  const double c = std::cos(b.yaw_rad), s = std::sin(b.yaw_rad);
  const Eigen::Vector2d d = p - b.center_m.head<2>();
  const Eigen::Vector2d local(c * d.x() + s * d.y(), -s * d.x() + c * d.y());
  return (local.cwiseAbs() - b.size_m.head<2>() / 2).cwiseMax(0.0).norm();
}

std::shared_ptr<const OccupancyGrid> building_plan() {
  static const auto plan = std::make_shared<const OccupancyGrid>(floor_plan_of(building_cloud(), building_segmentation()));
  return plan;
}
}  // namespace

TEST_CASE("the start is a known pose with room around it, else the floor plan's clearest free place", "[semantic]") {
  ExportSettings st;
  st.floor_plan = building_plan();
  const double need = st.robot_half_width_m + st.robot_margin_m;
  const auto& plan = *st.floor_plan;
  const Eigen::Vector3d start = robot_start(building_net(), st);
  // Free around it: seen floor, nothing at the robot's height, no solid.
  for (double dx = -need; dx <= need; dx += plan.resolution_m)
    for (double dy = -need; dy <= need; dy += plan.resolution_m) {
      if (std::hypot(dx, dy) > need - plan.resolution_m) continue;
      const Eigen::Vector2i c = plan.cell_of(start.head<2>() + Eigen::Vector2d(dx, dy));
      REQUIRE(plan.contains(c.x(), c.y()));
      CHECK(plan.at(c.x(), c.y()) == CellState::Free);
    }
  for (const auto& b : model_boxes(building_net(), st))
    if (b.kind != "floor" && b.kind != "ceiling" && b.center_m.z() - b.size_m.z() / 2 < st.robot_height_m) {
      INFO(b.name);
      CHECK(footprint_distance(b, start.head<2>()) >= need - 0.05);
    }
  // Scan poses: the first with room around it (not the one against the west wall).
  st.known_poses = {{-3.7, 0.0, 0.0}, {0.0, 0.0, 0.5}, {6.0, -1.0, 3.1}};
  CHECK(robot_start(building_net(), st).isApprox(Eigen::Vector3d(0.0, 0.0, 0.5)));
}

TEST_CASE("the floor plan of a cloud with a thick floor (a Kinect's OctoMap) is free where only the floor is", "[semantic]") {
  // A 4 x 4 m floor 18 cm thick (-9 to +9 cm, most near 0: a Kinect's
  // depth noise, as freiburg1_360.bt's), and a 0.4 m cube on it.
  Cloud c;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 0.09);
  for (double x = -2; x <= 2; x += 0.02)
    for (double y = -2; y <= 2; y += 0.02)
      c.points.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(u(rng) - u(rng)));
  for (double x = 0.5; x <= 0.9; x += 0.02)
    for (double y = 0.5; y <= 0.9; y += 0.02)
      for (double z = 0.1; z <= 0.4; z += 0.02) c.points.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
  const OccupancyGrid g = floor_plan_of(c, segment(c));
  int free = 0, floor = 0;
  for (int r = 0; r < g.height; ++r)
    for (int col = 0; col < g.width; ++col) {
      const Eigen::Vector2d p = g.center(col, r);
      if (p.cwiseAbs().maxCoeff() > 1.9) continue;
      if (p.x() > 0.4 && p.x() < 1.0 && p.y() > 0.4 && p.y() < 1.0) {
        if (p.x() > 0.55 && p.x() < 0.85 && p.y() > 0.55 && p.y() < 0.85) CHECK(g.at(col, r) == CellState::Occupied);
        continue;
      }
      ++floor;
      free += g.at(col, r) == CellState::Free ? 1 : 0;
    }
  CHECK(free == floor);
}

TEST_CASE("no start where nothing is known to be free, nor inside a box over the whole building", "[semantic]") {
  ExportSettings st;
  auto unknown = std::make_shared<OccupancyGrid>(*building_plan());
  std::fill(unknown->cells.begin(), unknown->cells.end(), CellState::Unknown);
  st.floor_plan = unknown;
  CHECK_THROWS_WITH(robot_start(building_net(), st), Catch::Contains("no free place") && Catch::Contains("0.60 m clearance"));
  // The "obstacle" over the whole building: no start inside it, a clear refusal.
  Segmentation seg = building_segmentation();
  Obstacle all;
  all.center_m = {2.5, 1.25, 1.3};
  all.size_m = {14.0, 9.5, 2.6};
  seg.obstacles.push_back(all);
  st.floor_plan = building_plan();
  CHECK_THROWS_WITH(robot_start(SemanticNet(seg), st), Catch::Contains("no free place"));
}

TEST_CASE("the PNG map: each entity in its colour, free and unknown apart, labels apart, a true scale bar", "[semantic]") {
  const auto path = temp_file("map_layout.png");
  ExportSettings st;
  st.map_px_per_m = 40;
  const MapLayout l = map_layout(building_net(), &building_cloud(), st);
  write_map_png(path.string(), building_net(), &building_cloud(), st);
  const cv::Mat img = cv::imread(path.string(), cv::IMREAD_COLOR);
  REQUIRE(img.cols == l.cols);
  REQUIRE(img.rows == l.rows);
  const cv::Rect legend(l.legend_x, l.legend_y, l.legend_width, l.legend_height);
  std::vector<cv::Rect> boxes;
  for (const auto& b : l.labels) boxes.emplace_back(b.x, b.y, b.width, b.height);
  // Labels: inside the image, apart from each other and from the legend.
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    INFO(l.labels[i].text);
    CHECK((boxes[i] & cv::Rect(0, 0, l.cols, l.rows)) == boxes[i]);
    CHECK((boxes[i] & legend).empty());
    for (std::size_t j = i + 1; j < boxes.size(); ++j) CHECK((boxes[i] & boxes[j]).empty());
  }
  // Every door, the stairs and the obstacle have their label.
  int named = 0;
  for (const auto& b : l.labels) {
    const EntityKind k = building_net().entity(b.entity).kind;
    named += k == EntityKind::Door || k == EntityKind::Stairs || k == EntityKind::Obstacle;
  }
  const auto& seg = building_net().segmentation();
  CHECK(named == static_cast<int>(seg.doors.size() + seg.stairs.size() + seg.obstacles.size()));
  // Colours where the entities are (where no label or legend lies over them).
  const auto colour_at = [&](const Eigen::Vector2d& p) {
    const cv::Point q(static_cast<int>((p.x() - l.min_m.x()) * l.px_per_m), static_cast<int>((l.max_m.y() - p.y()) * l.px_per_m));
    bool covered = legend.contains(q);
    for (const auto& b : boxes) covered = covered || b.contains(q);
    INFO("at " << p.transpose());
    REQUIRE_FALSE(covered);
    return img.at<cv::Vec3b>(q);
  };
  const auto is = [](const cv::Vec3b& v, const unsigned char (&c)[3]) {
    return std::abs(v[0] - c[0]) < 10 && std::abs(v[1] - c[1]) < 10 && std::abs(v[2] - c[2]) < 10;
  };
  CHECK(is(colour_at({-4.0, -1.0}), map_colour::kWall));
  CHECK(is(colour_at({3.0, -0.2}), map_colour::kDoor));
  CHECK(is(colour_at({1.2, 4.0}), map_colour::kStairs));
  REQUIRE_FALSE(seg.obstacles.empty());
  CHECK(is(colour_at(seg.obstacles[0].center_m.head<2>()), map_colour::kObstacle));
  ExportSettings with_plan = st;
  with_plan.floor_plan = building_plan();
  CHECK(is(colour_at(robot_start(building_net(), with_plan).head<2>()), map_colour::kFree));
  CHECK(is(colour_at({-4.35, 1.0}), map_colour::kUnknown));  // beyond the west wall
  // The scale bar: scale_bar_m long at map_px_per_m, drawn black.
  CHECK(l.scale_bar_m > 0);
  CHECK(l.scale_bar_x1 - l.scale_bar_x0 == static_cast<int>(std::lround(l.scale_bar_m * st.map_px_per_m)));
  int dark = 0;
  for (int x = l.scale_bar_x0; x <= l.scale_bar_x1; ++x) dark += img.at<cv::Vec3b>(l.scale_bar_y, x)[1] < 60;
  CHECK(dark >= l.scale_bar_x1 - l.scale_bar_x0);
  std::filesystem::remove(path);
}
