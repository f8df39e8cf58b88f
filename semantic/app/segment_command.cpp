#include "semantic/app/segment_command.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <vector>

#include "semantic/cloud_io.hpp"
#include "semantic/floor_plan.hpp"
#include "semantic/occupancy_grid.hpp"
#include "semantic/segmentation.hpp"
#include "semantic/semantic_net.hpp"
#include "semantic/world_export.hpp"

namespace rise::semantic {
namespace {

struct SegmentOptions {
  std::string cloud;
  bool json = false;
  bool level = false;
  std::string out_dir;
  std::string name = "semantic";
  std::string image;            // a ROS map's image, replacing the one its YAML names
  double resolution_m = 0.05;   // a CARMEN log's grid
  FloorPlanSettings plan;
  SegmentationSettings cloud_settings;
};

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// A 2D map rather than a cloud: a ROS map_server YAML or a CARMEN log.
bool is_ros_map(const std::string& path) { return ends_with(path, ".yaml") || ends_with(path, ".yml"); }
bool is_carmen_log(const std::string& path) { return ends_with(path, ".log") || ends_with(path, ".log.gz"); }

// The occupied cells as points at half the wall height: map.png draws them in grey.
Cloud occupied_cells(const OccupancyGrid& grid, double z_m) {
  Cloud c;
  for (int r = 0; r < grid.height; ++r)
    for (int col = 0; col < grid.width; ++col)
      if (grid.at(col, r) == CellState::Occupied) {
        const Eigen::Vector2d p = grid.center(col, r);
        c.points.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(z_m));
      }
  return c;
}

// Logs go to stderr: stdout carries the entities (JSON with --json).
std::shared_ptr<spdlog::logger> logger() {
  auto l = spdlog::get("segment");
  return l ? l : spdlog::stderr_color_mt("segment");
}

int run_segment(const SegmentOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  const bool plan = is_ros_map(o.cloud) || is_carmen_log(o.cloud);
  OccupancyGrid grid;
  Cloud cloud;
  std::vector<Eigen::Vector3d> scan_poses;  // where a CARMEN log's laser stood, in order
  if (is_ros_map(o.cloud)) {
    grid = read_ros_map(o.cloud, o.image);
  } else if (is_carmen_log(o.cloud)) {
    const auto scans = read_carmen_log(o.cloud);
    grid = grid_from_scans(scans, o.resolution_m);
    for (const auto& s : scans) scan_poses.push_back(s.pose);
  } else {
    cloud = read_cloud(o.cloud);
    if (o.level) {
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      T.linear() = levelling_rotation(cloud);
      cloud = transformed(cloud, T);
    }
  }
  const auto t1 = std::chrono::steady_clock::now();
  SemanticNet net(plan ? segment_floor_plan(grid, o.plan) : segment(cloud, o.cloud_settings));
  const auto t2 = std::chrono::steady_clock::now();
  if (plan) cloud = occupied_cells(grid, o.plan.wall_height_m / 2);
  const auto ms = [](auto a, auto b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
  if (o.json) {
    std::fputs(to_json(net).c_str(), stdout);
  } else {
    const auto& seg = net.segmentation();
    if (plan)
      std::printf("%s: %d x %d cells of %.3f m, read %.0f ms, segmented %.0f ms\n", o.cloud.c_str(), grid.width,
                  grid.height, grid.resolution_m, ms(t0, t1), ms(t1, t2));
    else
      std::printf("%s: %zu points, read %.0f ms, segmented %.0f ms\n", o.cloud.c_str(), cloud.size(), ms(t0, t1),
                  ms(t1, t2));
    std::printf("floor %.3f m", seg.floor.height_m);
    if (seg.ceiling.found) std::printf(", ceiling %.3f m", seg.ceiling.height_m);
    std::printf("; %zu walls, %zu doors, %zu stairs, %zu obstacles", seg.walls.size(), seg.doors.size(),
                seg.stairs.size(), seg.obstacles.size());
    if (seg.oversize_clusters_dropped > 0)
      std::printf(" (%d clusters over %.1f m or across a doorway dropped)", seg.oversize_clusters_dropped,
                  SegmentationSettings{}.obstacle_max_size_m);
    std::printf("\n");
    for (const auto& e : net.entities()) {
      std::printf("  %-16s at (%7.3f, %7.3f, %6.3f) size %.3f x %.3f x %.3f yaw %6.1f deg", e.name.c_str(),
                  e.position_m.x(), e.position_m.y(), e.position_m.z(), e.size_m.x(), e.size_m.y(), e.size_m.z(),
                  e.yaw_rad * 180.0 / M_PI);
      if (e.kind == EntityKind::Stairs) {
        const auto& s = seg.stairs[static_cast<std::size_t>(e.index)];
        std::printf("  %d steps, riser %.3f m, tread %.3f m", s.steps, s.riser_m, s.tread_m);
      } else if (e.kind == EntityKind::Door) {
        const auto& d = seg.doors[static_cast<std::size_t>(e.index)];
        std::printf("  width %.3f m, height %.3f m%s%s", d.width_m, d.height_m, d.lintel ? ", lintel" : "",
                    d.panel ? ", panel" : "");
      }
      std::printf("\n");
    }
  }
  if (!o.out_dir.empty()) {
    std::filesystem::create_directories(o.out_dir);
    const std::filesystem::path dir(o.out_dir);
    ExportSettings st;
    st.world_name = o.name;
    // A 2D map is its own floor plan; a cloud's is made from it.
    st.floor_plan = std::make_shared<OccupancyGrid>(plan ? grid : floor_plan_of(cloud, net.segmentation(), st));
    // A cloud's origin is where its scanner stood: a single scan's sensor
    // frame, or the first scan's in a map SLAM made (rise-semantic map's
    // map.pcd, 3DTK, PCL's scans). A pose the robot has been at.
    if (!plan && !o.level) st.known_poses.push_back(Eigen::Vector3d::Zero());
    // A CARMEN log has the robot's own path: it starts where the robot did
    // (the laser's pose; the base is a few cm behind it), or at the first
    // pose after it with room, in the part of the building the robot drove.
    st.known_poses.insert(st.known_poses.end(), scan_poses.begin(), scan_poses.end());
    // The map first: it shows why, when the world file has no start.
    write_map_png((dir / "map.png").string(), net, &cloud, st);
    write_text_file((dir / "world.sdf").string(), sdf_world(net, st));
    write_text_file((dir / "model.obj").string(), obj_mesh(net, st));
    write_text_file((dir / "world.yaml").string(), world_yaml(net, st));
    logger()->info("wrote world.yaml, world.sdf, model.obj, map.png to {}", o.out_dir);
  }
  return 0;
}

}  // namespace

void add_segment_command(CLI::App& app) {
  auto opts = std::make_shared<SegmentOptions>();
  CLI::App* sub = app.add_subcommand(
      "segment", "find floor, ceiling, walls, doors, stairs and obstacles in one registered cloud or 2D map");
  sub->add_option("CLOUD", opts->cloud,
                  "registered cloud, world frame, z up (.pcd .ply .xyz .3d .vtk .bt .ot); or a 2D map: ROS map_server "
                  "MAP.yaml, CARMEN log (.log .log.gz)")
      ->required();
  sub->add_option("--image", opts->image, "ROS map: the image to read instead of the one MAP.yaml names");
  sub->add_option("--resolution", opts->resolution_m, "CARMEN log: grid cell size, m")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 1.0));
  sub->add_option("--wall-height", opts->plan.wall_height_m, "2D map: height the walls are extruded to, m")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 20.0));
  sub->add_option("--door-height", opts->plan.door_height_m, "2D map: a doorway's lintel underside, m")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 20.0));
  sub->add_flag("--json", opts->json, "print the entities and relations as JSON");
  sub->add_flag("--level", opts->level, "level the cloud first (its floor made horizontal)");
  sub->add_flag("--walls-from-floor-plan", opts->cloud_settings.walls_from_floor_plan,
                "cloud: walls and doorways from the floor plan of its wall band (one wall per slab)");
  sub->add_option("--out-dir,-o", opts->out_dir,
                  "also write map.png, world.sdf, model.obj and world.yaml here (exit 1 when the robot has no room to start)");
  sub->add_option("--name", opts->name, "world name in the files written")->capture_default_str();
  sub->callback([opts] {
    if (opts->plan.door_height_m >= opts->plan.wall_height_m)
      throw CLI::ValidationError("--door-height", "must be below --wall-height (the lintel is wall above the door)");
    int rc = 0;
    try {
      rc = run_segment(*opts);
    } catch (const NoRobotStart& e) {  // the world cannot be driven: no right answer
      logger()->error("segment: {}", e.what());
      rc = 1;
    } catch (const std::exception& e) {
      logger()->error("segment: {}", e.what());
      rc = 2;
    }
    if (rc != 0) throw CLI::RuntimeError(rc);
  });
}

}  // namespace rise::semantic
