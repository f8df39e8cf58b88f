#pragma once

// Point-cloud files in and out: PCD (ASCII, binary, binary_compressed; read
// with PCL's reader), PLY (ascii and binary little/big endian), XYZ text, and
// 3DTK's `.3d` scans with their `.pose` (centimetres, left-handed y up,
// converted to the engine's metres, right-handed z up). Errors throw
// std::runtime_error naming the file and the line or byte offset.

#include "semantic/cloud.hpp"

#include <string>

namespace rise::semantic {

/// Reads a cloud, the format from the extension (.pcd .ply .xyz .3d).
Cloud read_cloud(const std::string& path);

/// Reads a scan: the cloud, and the pose beside it if there is one — the
/// simulator's `<stem>.pose` beside a `.pcd`, or 3DTK's `<stem>.pose` beside
/// a `.3d` — as T_world_scan.
Scan read_scan(const std::string& path);

/// Writes by extension (.pcd binary, .ply binary little endian, .xyz).
void write_cloud(const std::string& path, const Cloud& cloud);

/// 3DTK's coordinate convention (x right, y up, z forward, cm) to ours
/// (x forward, y left, z up, m), as a change of basis for points and poses.
Eigen::Vector3f from_3dtk_point(const Eigen::Vector3f& p_cm);
Eigen::Isometry3d from_3dtk_pose(const Eigen::Isometry3d& T_3dtk_cm);

}  // namespace rise::semantic
