#pragma once

// Point clouds as PCL's PCD files, version 0.7 (pointclouds.org, "The PCD
// (Point Cloud Data) file format"), written and read without PCL: FIELDS
// x y z as 4-byte floats, DATA ascii or binary, VIEWPOINT = the sensor's
// pose. Beside a scan's PCD, a `.pose` text file holds the same true pose
// at full double precision with the sim time (format in sim/README.md).

#include <Eigen/Geometry>

#include <cstdint>
#include <string>
#include <vector>

namespace rise::sim {

enum class PcdFormat { Ascii, Binary };

struct PointCloud {
  std::vector<Eigen::Vector3f> points;  ///< x y z of every point, file order
  uint32_t width = 0;
  uint32_t height = 1;
  Eigen::Isometry3d viewpoint = Eigen::Isometry3d::Identity();  ///< VIEWPOINT tx ty tz qw qx qy qz
};

/// Writes an unorganized cloud (HEIGHT 1): FIELDS x y z, SIZE 4, TYPE F.
/// Floats as the shortest text that reads back to the same float (ascii),
/// or little-endian IEEE 754 (binary). Throws std::runtime_error
/// "path: cannot write: <strerror>" when it cannot.
void write_pcd(const std::string& path, const std::vector<Eigen::Vector3f>& points, const Eigen::Isometry3d& viewpoint,
               PcdFormat format);

/// Reads a PCD v0.7 (or 0.6 without VIEWPOINT) file whose x, y, z fields
/// are 4-byte floats; other fields are skipped. DATA ascii or binary
/// (binary_compressed is refused). Throws std::runtime_error
/// "path:line: KEY: message".
PointCloud read_pcd(const std::string& path);

struct PoseFile {
  double time_s = 0.0;
  Eigen::Isometry3d T_world_sensor = Eigen::Isometry3d::Identity();
};

/// Writes the `.pose` text file; throws "path: cannot write: <strerror>".
void write_pose(const std::string& path, const Eigen::Isometry3d& T_world_sensor, double time_s);
/// Reads it back (position_m and orientation_wxyz; the matrix line is for
/// readers without quaternions). Throws "path:line: key: message".
PoseFile read_pose(const std::string& path);

}  // namespace rise::sim
