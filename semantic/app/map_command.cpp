#include "semantic/app/map_command.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "semantic/app/progress_bar.hpp"
#include "semantic/cloud_io.hpp"
#include "semantic/map_pipeline.hpp"

namespace rise::semantic {
namespace {

struct MapOptions {
  std::vector<std::string> scans;
  std::string out_dir;
  std::string name = "semantic";
  double voxel_m = SlamSettings{}.scan_voxel_m;
  double map_voxel_m = SlamSettings{}.map_voxel_m;
  std::string metric = "plane";
  int iterations = SlamSettings{}.icp.max_iterations;
  double max_dist_m = SlamSettings{}.icp.max_correspondence_m;
  std::string target = "nearest";
  int map_scans = SlamSettings{}.map_scans;
  double loop_radius_m = SlamSettings{}.loop_radius_m;
  int loop_separation = SlamSettings{}.loop_min_separation;
  double loop_max_rmse_m = SlamSettings{}.loop_max_rmse_m;
  double cell_m = SegmentationSettings{}.cell_m;
  bool no_level = false;
  int threads = 0;
};

constexpr double kDeg = 180.0 / M_PI;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

MapSettings settings_from(const MapOptions& o) {
  MapSettings s;
  s.slam.scan_voxel_m = o.voxel_m;
  s.slam.map_voxel_m = o.map_voxel_m;
  if (o.metric != "plane" && o.metric != "point")
    throw std::invalid_argument("--metric: '" + o.metric + "' is neither 'plane' nor 'point'");
  s.slam.icp.metric = o.metric == "plane" ? IcpMetric::PointToPlane : IcpMetric::PointToPoint;
  s.slam.icp.max_iterations = o.iterations;
  s.slam.icp.max_correspondence_m = o.max_dist_m;
  s.slam.icp.threads = o.threads;
  if (o.target != "nearest" && o.target != "last")
    throw std::invalid_argument("--target: '" + o.target + "' is neither 'nearest' nor 'last'");
  s.slam.target = o.target == "nearest" ? SlamTarget::NearestScans : SlamTarget::LastScans;
  s.slam.map_scans = o.map_scans;
  s.slam.loop_radius_m = o.loop_radius_m;
  s.slam.loop_min_separation = o.loop_separation;
  s.slam.loop_max_rmse_m = o.loop_max_rmse_m;
  if (!(o.cell_m > 0.0)) throw std::invalid_argument("--cell: must be > 0");
  s.segmentation.cell_m = o.cell_m;
  s.level = !o.no_level;
  s.exports.world_name = o.name;
  return s;
}

void print_found(const MapResult& r, std::size_t points_read, const std::vector<std::optional<Eigen::Isometry3d>>& guesses, double map_voxel_m) {
  const Segmentation& seg = r.net.segmentation();
  std::printf("%zu scans, %zu points read; map %zu points (%.3f m voxels)\n", guesses.size(), points_read, r.map.size(),
              map_voxel_m);
  std::printf("loops: %zu kept of %d tried", r.slam.loops.size(), r.slam.loop_candidates);
  for (const auto& l : r.slam.loops) std::printf("  %zu->%zu (rmse %.3f m)", l.from, l.to, l.rmse_m);
  std::printf("\n");
  double corrected_m = 0.0, corrected_rad = 0.0;
  for (std::size_t i = 0; i < guesses.size(); ++i) {
    if (!guesses[i]) continue;
    const Eigen::Isometry3d d = guesses[i]->inverse() * r.slam.T_world_scan[i];
    corrected_m = std::max(corrected_m, d.translation().norm());
    corrected_rad = std::max(corrected_rad, Eigen::AngleAxisd(d.linear()).angle());
  }
  std::printf("poses: the initial guess corrected by up to %.3f m / %.2f deg; levelled by %.2f deg\n", corrected_m,
              corrected_rad * kDeg, Eigen::AngleAxisd(r.T_level_slam.linear()).angle() * kDeg);
  std::printf("floor at %.3f m", seg.floor.height_m);
  if (seg.ceiling.found) std::printf(", ceiling at %.3f m (%.3f m above the floor)", seg.ceiling.height_m,
                                     seg.ceiling.height_m - seg.floor.height_m);
  std::printf("\n%zu walls, %zu doors, %zu stairs, %zu obstacles\n", seg.walls.size(), seg.doors.size(),
              seg.stairs.size(), seg.obstacles.size());
  for (std::size_t i = 0; i < seg.walls.size(); ++i) {
    const Wall& w = seg.walls[i];
    std::printf("  wall_%zu      (%7.3f, %7.3f) -> (%7.3f, %7.3f)  length %.3f m, height %.3f m, thickness %.3f m",
                i, w.from_m.x(), w.from_m.y(), w.to_m.x(), w.to_m.y(), w.length_m(), w.height_m, w.thickness_m);
    if (!w.openings.empty()) std::printf(", %zu opening(s)", w.openings.size());
    std::printf("\n");
  }
  for (std::size_t i = 0; i < seg.doors.size(); ++i) {
    const Door& d = seg.doors[i];
    std::printf("  door_%zu      at (%7.3f, %7.3f)  width %.3f m, height %.3f m, yaw %6.1f deg%s%s\n", i,
                d.center_m.x(), d.center_m.y(), d.width_m, d.height_m, d.yaw_rad * kDeg, d.lintel ? ", lintel" : "",
                d.panel ? ", panel" : "");
  }
  for (std::size_t i = 0; i < seg.stairs.size(); ++i) {
    const Stairs& s = seg.stairs[i];
    std::printf("  stairs_%zu    from (%7.3f, %7.3f) yaw %6.1f deg  %d steps, riser %.3f m, tread %.3f m, width %.3f m, "
                "landing %.3f m\n",
                i, s.start_m.x(), s.start_m.y(), s.yaw_rad * kDeg, s.steps, s.riser_m, s.tread_m, s.width_m,
                s.landing_m);
  }
  for (std::size_t i = 0; i < seg.obstacles.size(); ++i) {
    const Obstacle& o = seg.obstacles[i];
    std::printf("  obstacle_%zu  at (%7.3f, %7.3f, %6.3f)  size %.3f x %.3f x %.3f m\n", i, o.center_m.x(),
                o.center_m.y(), o.center_m.z(), o.size_m.x(), o.size_m.y(), o.size_m.z());
  }
}

int run_map(const MapOptions& o) {
  const MapSettings settings = settings_from(o);
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<Scan> scans;
  std::vector<std::string> names;
  std::size_t points = 0;
  {
    ProgressBar bar;
    for (std::size_t i = 0; i < o.scans.size(); ++i) {
      scans.push_back(read_scan(o.scans[i]));
      points += scans.back().cloud.size();
      names.push_back(scans.back().name);
      bar.update(i + 1, o.scans.size(), "read");
    }
  }
  const double read_s = seconds_since(t0);
  std::size_t without_pose = 0;
  for (const auto& s : scans) without_pose += s.T_world_scan ? 0 : 1;
  if (without_pose > 0) spdlog::warn("{} of {} scans have no pose beside them: chained from the previous one", without_pose, scans.size());

  std::vector<std::optional<Eigen::Isometry3d>> guesses;  // for the correction printed
  for (const auto& s : scans) guesses.push_back(s.T_world_scan);
  MapResult r = [&] {
    ProgressBar bar;
    return build_map(std::move(scans), settings, bar.callback());
  }();
  if (!r.slam.refused.empty()) {
    // A world built on a match that did not hold would look right and be
    // wrong: no files, one line naming the scans.
    std::string which;
    for (const std::size_t i : r.slam.refused) {
      const IcpResult& m = r.slam.sequential[i];
      which += fmt::format("{}{} ({}, {:.0f} % paired)", which.empty() ? "" : ", ", names[i],
                           m.inlier_ratio < settings.slam.match_min_inlier_ratio ? "too few pairs" : "did not converge",
                           100.0 * m.inlier_ratio);
    }
    spdlog::error("map: {} of {} scans did not register onto the scans before them: {}; no map written",
                  r.slam.refused.size(), names.size(), which);
    return 1;
  }
  const double export_s = write_map_files(o.out_dir, r, names, settings.exports);

  print_found(r, points, guesses, settings.slam.map_voxel_m);
  const auto& t = r.slam.timings;
  std::printf("timings: read %.3f s, slam %.3f s (preprocess %.3f, sequential %.3f, loops %.3f, relaxation %.3f, "
              "map %.3f), level %.3f s, segment %.3f s, export %.3f s, total %.3f s\n",
              read_s, r.timings.slam_s, t.preprocess_s, t.sequential_s, t.loops_s, t.relaxation_s, t.map_s,
              r.timings.level_s, r.timings.segment_s, export_s, seconds_since(t0));
  std::printf("wrote world.yaml, map.png, world.sdf, mesh.obj, map.pcd, poses.txt, entities.json to %s\n",
              o.out_dir.c_str());
  return 0;
}

}  // namespace

void add_map_command(CLI::App& app) {
  auto opts = std::make_shared<MapOptions>();
  CLI::App* sub = app.add_subcommand(
      "map", "scans -> 6D SLAM -> levelled map -> entities -> world.yaml, map.png, world.sdf, mesh.obj, map.pcd, "
             "poses.txt, entities.json");
  sub->add_option("SCANS", opts->scans, "scans in order (.pcd + .pose, .3d + .pose, .ply, .xyz)")->required();
  sub->add_option("-o,--out-dir", opts->out_dir, "where the files go (created)")->required();
  sub->add_option("--name", opts->name, "world name in the files written")->capture_default_str();
  sub->add_option("--voxel", opts->voxel_m, "scan voxel filter for matching (m; 0: none)")->capture_default_str();
  sub->add_option("--map-voxel", opts->map_voxel_m, "merged map's voxel filter (m; 0: none)")->capture_default_str();
  sub->add_option("--metric", opts->metric, "ICP metric: plane or point")->capture_default_str();
  sub->add_option("--iterations", opts->iterations, "ICP iterations per match")->capture_default_str();
  sub->add_option("--max-dist", opts->max_dist_m, "ICP's first pairing distance (m)")->capture_default_str();
  sub->add_option("--target", opts->target, "match each scan onto the 'nearest' or the 'last' earlier scans")
      ->capture_default_str();
  sub->add_option("--map-scans", opts->map_scans, "earlier scans each scan is matched onto")->capture_default_str();
  sub->add_option("--loop-radius", opts->loop_radius_m, "loop candidates: scan centres this close (m)")
      ->capture_default_str();
  sub->add_option("--loop-separation", opts->loop_separation, "... and at least this many scans apart")
      ->capture_default_str();
  sub->add_option("--loop-rmse", opts->loop_max_rmse_m, "a loop match is kept up to this rmse (m)")
      ->capture_default_str();
  sub->add_option("--cell", opts->cell_m, "segmentation's floor-plane cell (m)")->capture_default_str();
  sub->add_flag("--no-level", opts->no_level, "keep the map as SLAM made it (no floor levelling)");
  sub->add_option("--threads", opts->threads, "ICP threads (0: OpenMP's default)")->capture_default_str();
  sub->callback([opts] {
    int rc = 0;
    try {
      rc = run_map(*opts);
    } catch (const NoRobotStart& e) {  // the world cannot be driven: no right answer
      spdlog::error("map: {}", e.what());
      rc = 1;
    } catch (const std::exception& e) {
      spdlog::error("map: {}", e.what());
      rc = 2;
    }
    if (rc != 0) throw CLI::RuntimeError(rc);
  });
}

}  // namespace rise::semantic
