#pragma once

// OctoMap's files (Hornung et al., "OctoMap: an efficient probabilistic 3D
// mapping framework based on octrees", 2013; octomap 1.9): the binary tree
// `.bt` that octomap_server and writeBinary() save (occupied / free per
// leaf) and the full tree `.ot` of AbstractOcTree::write() (log-odds per
// node). Our own reader: no liboctomap. Errors throw std::runtime_error,
// "path:line: key: message" in the header and "path: byte N: message" in
// the tree.

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "semantic/cloud.hpp"

namespace rise::semantic {

/// One leaf of the tree: a cube of `size_m` = resolution · 2^(16 − depth)
/// (octomap prunes eight equal children into their parent, so a leaf above
/// depth 16 stands for all its cells).
struct OctoMapLeaf {
  Eigen::Vector3d centre_m;
  double size_m = 0;
  int depth = 16;  ///< 0 = the root, 16 = one cell of `resolution_m`
  bool occupied = false;
  std::optional<float> log_odds;  ///< `.ot` only: `.bt` keeps occupied / free
};

struct OctoMap {
  std::string tree_type;  ///< the header's `id`: OcTree, ColorOcTree, OcTreeStamped
  double resolution_m = 0;
  uint64_t nodes = 0;        ///< every node, the root included (the header's `size`)
  uint64_t inner_nodes = 0;  ///< nodes with children; the rest are `leaves`
  std::vector<OctoMapLeaf> leaves;  ///< in the file's depth-first order
  uint64_t occupied_cells = 0;      ///< occupied leaves in cells of `resolution_m` (saturates)
};

/// Reads a `.bt` or `.ot` (which one from its first line, not its name).
OctoMap read_octomap(const std::string& path);

/// The centres of the occupied cells at the finest resolution: an occupied
/// leaf of depth d gives 8^(16 − d) points (`map.occupied_cells` in all;
/// check it before calling on a file from outside).
Cloud occupied_voxels(const OctoMap& map);

namespace formats {

/// Parses a `.bt` or `.ot` file's bytes (errors name `path`). Also the fuzz
/// target's entry point.
OctoMap parse_octomap(const std::string& path, std::string_view bytes);

/// parse_octomap, then occupied_voxels; refused ("path: N occupied cells
/// ...") when they would be more than `max_points` points.
Cloud octomap_cloud(const std::string& path, std::string_view bytes, uint64_t max_points);

}  // namespace formats
}  // namespace rise::semantic
