#pragma once

// The cloud and pose file formats that need no PCL, as text or bytes in,
// clouds and poses out (semantic/cloud_io.hpp reads the files and adds the
// PCD data through PCL's reader). Each throws std::runtime_error naming
// `path` and the line ("path:line: message") or, in binary data, the byte
// offset ("path: byte N: message"). Also the fuzz targets' entry points.

#include <Eigen/Geometry>

#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "semantic/cloud.hpp"
#include "semantic/text_reading.hpp"

namespace rise::semantic::formats {

/// A PCD header (pointclouds.org, "The PCD file format") as our own check
/// read it: PCL reports problems on its console without a line; this names
/// the line and the key, and sizes the data before PCL touches it.
struct PcdHeader {
  std::vector<std::string> fields;
  std::vector<int> sizes, counts;
  std::vector<char> types;
  uint64_t width = 0, height = 1, points = 0;
  std::string data;
  size_t data_offset = 0;  // first byte after the DATA line
  size_t data_line = 0;
  std::map<std::string, size_t> line_of;  // key -> its line
  double viewpoint[7] = {0, 0, 0, 1, 0, 0, 0};  // tx ty tz qw qx qy qz
};

/// The header as a canonical PCD v0.7 text (one line per key, in order,
/// ending with the DATA line): what PCL's reader is given instead of the
/// file's own header, so that it only ever parses a header we checked.
std::string canonical_pcd_header(const PcdHeader& h);

/// Parses and checks a PCD header, then checks the data against it: binary
/// sizes against the file's, binary_compressed's size words, ascii's value
/// counts per line.
PcdHeader check_pcd(const std::string& path, std::string_view text);

/// PLY (ascii, binary little/big endian): the vertex element's x y z and,
/// if all three are there, nx ny nz; other properties and elements skipped.
Cloud parse_ply(const std::string& path, std::string_view text);
/// Legacy VTK (`# vtk DataFile Version x.y`, ASCII or BINARY big endian):
/// the POINTS of a POLYDATA, UNSTRUCTURED_GRID or STRUCTURED_GRID and, if
/// there, POINT_DATA's NORMALS; cells and every other attribute read past.
Cloud parse_vtk(const std::string& path, std::string_view text);
/// "x y z" or "x y z nx ny nz" per line; '#' lines are comments.
Cloud parse_xyz(const std::string& path, std::string_view text);
/// 3DTK's uos `.3d`: an optional "W x H" header line, then x y z in cm,
/// converted to ours (from_3dtk_point).
Cloud parse_3d(const std::string& path, std::string_view text);
/// 3DTK's `.pose` (x y z cm, then roll pitch yaw degrees), converted to ours.
Eigen::Isometry3d parse_3dtk_pose(const std::string& path, std::string_view text);
/// 3DTK's `.frames`: one column-major 4x4 and a colour code per line, converted to ours.
std::vector<Eigen::Isometry3d> parse_3dtk_frames(const std::string& path, std::string_view text);
/// 3DTK's `config.ini` beside its scans: the range limits `min` and `max`
/// (cm; 0 for max: none). A point at or beyond max is a missing return.
struct Range3dtk {
  double min_m = 0.0, max_m = 0.0;
};
Range3dtk parse_3dtk_config(const std::string& path, std::string_view text);
/// The simulator's `.pose` (sim/README.md, "Scan files").
Eigen::Isometry3d parse_sim_pose(const std::string& path, std::string_view text);

std::string lower_extension(const std::string& path);

}  // namespace rise::semantic::formats
