#pragma once

// Point-cloud files in and out: PCD (ASCII, binary, binary_compressed; read
// with PCL's reader), PLY (ascii and binary little/big endian), XYZ text,
// legacy VTK, OctoMap's .bt/.ot (the occupied cells' centres), and 3DTK's
// `.3d` scans with their `.pose` (centimetres, left-handed y up, converted
// to the engine's metres, right-handed z up). Errors throw
// std::runtime_error naming the file and the line or byte offset.

#include "semantic/cloud.hpp"

#include <string>
#include <vector>

namespace rise::semantic {

/// Reads a cloud, the format from the extension (.pcd .ply .xyz .3d .vtk .bt
/// .ot; an OctoMap gives one point per occupied cell of its resolution).
Cloud read_cloud(const std::string& path);

/// Parses `contents` as the file `path` would be read (format from its
/// extension; errors name `path`). PCL's reader reads files only: a PCD's
/// checked header (rewritten canonically) and data go through a temporary
/// file, as they do for read_cloud.
Cloud parse_cloud(const std::string& path, const std::string& contents);

/// Reads a scan: the cloud, and the pose beside it if there is one — the
/// simulator's `<stem>.pose` beside a `.pcd`, or 3DTK's `<stem>.pose` beside
/// a `.3d` — as T_world_scan.
Scan read_scan(const std::string& path);

/// Writes by extension (.pcd binary, .ply binary little endian, .xyz).
void write_cloud(const std::string& path, const Cloud& cloud);

/// 3DTK's `.pose`: "x y z" (cm) then "roll pitch yaw" (degrees), as
/// slam6d's EulerToMatrix4 reads them (R = Rx·Ry·Rz), converted to ours.
Eigen::Isometry3d read_3dtk_pose(const std::string& path);

/// 3DTK's `.frames` (slam6d's output): per line a 4x4 column-major
/// (OpenGL) matrix and a colour code, one line per registration step; the
/// last line is the final pose. Converted to ours.
std::vector<Eigen::Isometry3d> read_3dtk_frames(const std::string& path);

/// slam6d's pose from position (cm) and Euler angles (rad), in 3DTK's frame.
Eigen::Isometry3d euler_3dtk(const Eigen::Vector3d& position_cm, const Eigen::Vector3d& angles_rad);

/// 3DTK's coordinate convention (x right, y up, z forward, cm) to ours
/// (x forward, y left, z up, m), as a change of basis for points and poses.
Eigen::Vector3f from_3dtk_point(const Eigen::Vector3f& p_cm);
Eigen::Isometry3d from_3dtk_pose(const Eigen::Isometry3d& T_3dtk_cm);

}  // namespace rise::semantic
