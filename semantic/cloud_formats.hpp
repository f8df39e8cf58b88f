#pragma once

// The cloud and pose file formats that need no PCL, as text or bytes in,
// clouds and poses out (semantic/cloud_io.hpp reads the files and adds the
// PCD data through PCL's reader). Each throws std::runtime_error naming
// `path` and the line ("path:line: message") or, in binary data, the byte
// offset ("path: byte N: message"). Also the fuzz targets' entry points.

#include <Eigen/Geometry>

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "semantic/cloud.hpp"

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
/// "x y z" or "x y z nx ny nz" per line; '#' lines are comments.
Cloud parse_xyz(const std::string& path, std::string_view text);
/// 3DTK's uos `.3d`: an optional "W x H" header line, then x y z in cm,
/// converted to ours (from_3dtk_point).
Cloud parse_3d(const std::string& path, std::string_view text);
/// 3DTK's `.pose` (x y z cm, then roll pitch yaw degrees), converted to ours.
Eigen::Isometry3d parse_3dtk_pose(const std::string& path, std::string_view text);
/// 3DTK's `.frames`: one column-major 4x4 and a colour code per line, converted to ours.
std::vector<Eigen::Isometry3d> parse_3dtk_frames(const std::string& path, std::string_view text);
/// The simulator's `.pose` (sim/README.md, "Scan files").
Eigen::Isometry3d parse_sim_pose(const std::string& path, std::string_view text);

std::string read_file(const std::string& path);  ///< throws "path: cannot open: <strerror>"
std::string lower_extension(const std::string& path);
[[noreturn]] void fail_line(const std::string& path, size_t line, const std::string& message);
[[noreturn]] void fail_byte(const std::string& path, size_t byte, const std::string& message);

// Text helpers shared by the readers of text formats (here and occupancy_grid.cpp).
/// The whitespace-separated words of `line`.
std::vector<std::string_view> words(std::string_view line);

template <typename T>
bool parse(std::string_view s, T& v) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc{} && p == s.data() + s.size();
}

template <typename T>
T number(std::string_view s, const std::string& path, size_t line, std::string_view what) {
  T v{};
  if (!parse(s, v)) fail_line(path, line, std::string(what) + ": not a number: '" + std::string(s) + "'");
  return v;
}

// Text split into lines with their 1-based numbers; '\r' dropped.
struct Lines {
  std::string_view text;
  size_t pos = 0;
  size_t number = 0;
  bool next(std::string_view& line) {
    if (pos >= text.size()) return false;
    const size_t end = std::min(text.find('\n', pos), text.size());
    line = text.substr(pos, end - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos = end + 1;
    ++number;
    return true;
  }
};

}  // namespace rise::semantic::formats
