#pragma once

// The semantic engine end to end (seed paper, section 3): scans → 6D SLAM
// (slam.hpp) → the merged map levelled (its floor made horizontal) →
// segmentation (segmentation.hpp) → the semantic net → the environment
// model (world_export.hpp). What `rise-semantic map` runs; the program reads
// the scans and writes the files (write_map_files).

#include <Eigen/Geometry>

#include <string>
#include <vector>

#include "semantic/cloud.hpp"
#include "semantic/segmentation.hpp"
#include "semantic/semantic_net.hpp"
#include "semantic/slam.hpp"
#include "semantic/world_export.hpp"

namespace rise::semantic {

struct MapSettings {
  SlamSettings slam = [] {
    SlamSettings s;
    s.target = SlamTarget::NearestScans;  // robot runs come back the way they went
    return s;
  }();
  bool level = true;  ///< turn the map about the origin so that its floor is horizontal
  SegmentationSettings segmentation;
  ExportSettings exports;
};

/// Wall-clock seconds of each stage after reading.
struct MapTimings {
  double slam_s = 0.0;
  double level_s = 0.0;
  double segment_s = 0.0;  ///< segmentation + semantic net
  double total_s = 0.0;
};

struct MapResult {
  SlamResult slam;                 ///< poses and map in the SLAM frame (scan 0's guess)
  Eigen::Isometry3d T_level_slam;  ///< the levelling rotation (identity when not levelled)
  std::vector<Eigen::Isometry3d> T_map_scan;  ///< the final poses in the levelled frame
  Cloud map;                       ///< the merged map in the levelled frame
  SemanticNet net;                 ///< the entities found in `map`
  MapTimings timings;
};

/// Runs SLAM over `scans`, levels the merged map and segments it. Throws
/// std::invalid_argument for what slam() or segment() refuse (no scans, an
/// empty scan, bad settings, a map without a floor). Allocates; never prints.
MapResult build_map(std::vector<Scan> scans, const MapSettings& settings = {}, const SlamProgress& progress = {});

/// `poses.txt`: a comment header, then per scan one line
/// `name x y z qw qx qy qz` (metres; the unit quaternion of T_map_scan,
/// the sensor frame's pose in the levelled map frame).
std::string poses_text(const std::vector<std::string>& names, const std::vector<Eigen::Isometry3d>& T_map_scan);

/// The files of a map in `dir` (created): world.yaml (the simulator's world
/// file), map.png, world.sdf, mesh.obj, map.pcd (the merged map), poses.txt
/// and entities.json (to_json). `names`: the scans', for poses.txt. Returns
/// the seconds it took. Throws std::runtime_error naming the file that
/// cannot be written.
double write_map_files(const std::string& dir, const MapResult& result, const std::vector<std::string>& names,
                       const ExportSettings& settings = {});

}  // namespace rise::semantic
