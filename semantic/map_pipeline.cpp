#include "semantic/map_pipeline.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "semantic/cloud_io.hpp"

namespace rise::semantic {
namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

MapResult build_map(std::vector<Scan> scans, const MapSettings& settings, const SlamProgress& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  SlamResult slam_result = slam(std::move(scans), settings.slam, progress);
  const auto t1 = std::chrono::steady_clock::now();
  Eigen::Isometry3d T_level = Eigen::Isometry3d::Identity();
  if (settings.level) T_level.linear() = levelling_rotation(slam_result.map, settings.segmentation);
  Cloud map = transformed(slam_result.map, T_level);
  std::vector<Eigen::Isometry3d> T_map_scan;
  for (const auto& T : slam_result.T_world_scan) T_map_scan.push_back(T_level * T);
  const auto t2 = std::chrono::steady_clock::now();
  SemanticNet net(segment(map, settings.segmentation));
  MapTimings timings;
  timings.slam_s = std::chrono::duration<double>(t1 - t0).count();
  timings.level_s = std::chrono::duration<double>(t2 - t1).count();
  timings.segment_s = seconds_since(t2);
  timings.total_s = seconds_since(t0);
  return MapResult{std::move(slam_result), T_level, std::move(T_map_scan), std::move(map), std::move(net), timings};
}

std::string poses_text(const std::vector<std::string>& names, const std::vector<Eigen::Isometry3d>& T_map_scan) {
  std::string out =
      "# rise-semantic map: the pose of each scan's sensor frame in the map frame (world.yaml's x, y;\n"
      "# z of the cloud, levelled), one line per scan: name x y z (m) qw qx qy qz (unit quaternion)\n";
  char line[256];
  for (std::size_t i = 0; i < T_map_scan.size(); ++i) {
    const Eigen::Vector3d t = T_map_scan[i].translation();
    const Eigen::Quaterniond q(T_map_scan[i].linear());
    std::snprintf(line, sizeof line, " %.6f %.6f %.6f %.9f %.9f %.9f %.9f\n", t.x(), t.y(), t.z(), q.w(), q.x(), q.y(),
                  q.z());
    out += (i < names.size() ? names[i] : "scan" + std::to_string(i)) + line;
  }
  return out;
}

double write_map_files(const std::string& dir, const MapResult& result, const std::vector<std::string>& names,
                       const ExportSettings& settings) {
  const auto t0 = std::chrono::steady_clock::now();
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir + ": cannot create the output directory: " + ec.message());
  const std::filesystem::path d(dir);
  // The robot stood at the scan poses; the floor plan is the map's.
  ExportSettings st = settings;
  if (st.known_poses.empty())
    for (const auto& T : result.T_map_scan) {
      const Eigen::Vector3d x = T.linear().col(0);
      st.known_poses.emplace_back(T.translation().x(), T.translation().y(), std::atan2(x.y(), x.x()));
    }
  if (!st.floor_plan) st.floor_plan = std::make_shared<OccupancyGrid>(floor_plan_of(result.map, result.net.segmentation(), st));
  write_text_file((d / "world.yaml").string(), world_yaml(result.net, st));
  write_text_file((d / "world.sdf").string(), sdf_world(result.net, st));
  write_text_file((d / "mesh.obj").string(), obj_mesh(result.net, st));
  write_text_file((d / "entities.json").string(), to_json(result.net));
  write_text_file((d / "poses.txt").string(), poses_text(names, result.T_map_scan));
  write_map_png((d / "map.png").string(), result.net, &result.map, st);
  write_cloud((d / "map.pcd").string(), result.map);
  return seconds_since(t0);
}

}  // namespace rise::semantic
