#include "sim/pcd_file.hpp"

#include <bit>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string_view>

#include "semantic/text_reading.hpp"

namespace rise::sim {
namespace {

namespace formats = semantic::formats;

static_assert(std::endian::native == std::endian::little, "PCD binary data is little-endian");

// Shortest text that reads back to the same value (std::to_chars without a
// precision), locale-independent.
template <typename T>
void put(std::string& out, T v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

void write_file(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error(path + ": cannot write: " + std::strerror(errno));
}

// `text` as a number, else "where: cannot read 'text'". "nan" is what PCL
// writes for an invalid point; from_chars reads it too.
template <typename T>
T number(std::string_view text, const std::string& where) {
  T v{};
  if (!formats::parse(text, v)) throw std::runtime_error(where + ": cannot read '" + std::string(text) + "'");
  return v;
}

Eigen::Isometry3d pose_from(const double t[3], const double q_wxyz[4]) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translate(Eigen::Vector3d(t[0], t[1], t[2]));
  T.rotate(Eigen::Quaterniond(q_wxyz[0], q_wxyz[1], q_wxyz[2], q_wxyz[3]).normalized());
  return T;
}

// "tx ty tz qw qx qy qz": PCD's VIEWPOINT and the .pose file's first lines.
void append_pose(std::string& out, const Eigen::Isometry3d& T) {
  const Eigen::Vector3d t = T.translation();
  const Eigen::Quaterniond q(T.rotation());
  for (double v : {t.x(), t.y(), t.z()}) {
    out += ' ';
    put(out, v);
  }
  for (double v : {q.w(), q.x(), q.y(), q.z()}) {
    out += ' ';
    put(out, v);
  }
}

}  // namespace

void write_pcd(const std::string& path, const std::vector<Eigen::Vector3f>& points, const Eigen::Isometry3d& viewpoint,
               PcdFormat format) {
  const std::string n = std::to_string(points.size());
  std::string out = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
                    "COUNT 1 1 1\nWIDTH " + n + "\nHEIGHT 1\nVIEWPOINT";
  append_pose(out, viewpoint);
  out += "\nPOINTS " + n + "\nDATA ";
  if (format == PcdFormat::Binary) {
    out += "binary\n";
    const std::size_t header = out.size();
    out.resize(header + points.size() * 3 * sizeof(float));
    char* p = out.data() + header;
    for (const auto& pt : points) {
      std::memcpy(p, pt.data(), 3 * sizeof(float));
      p += 3 * sizeof(float);
    }
  } else {
    out += "ascii\n";
    out.reserve(out.size() + points.size() * 30);
    for (const auto& pt : points) {
      put(out, pt.x());
      out += ' ';
      put(out, pt.y());
      out += ' ';
      put(out, pt.z());
      out += '\n';
    }
  }
  write_file(path, out);
}

PointCloud read_pcd(const std::string& path) {
  const std::string text = formats::read_file(path);
  PointCloud cloud;
  std::vector<std::string> fields, sizes, types, counts;
  std::size_t points = 0;
  bool have_points = false;
  std::string data;
  formats::Lines lines{text};
  std::string_view l;
  std::string where;
  const auto fail = [&](const std::string& key, const std::string& what) -> void {
    formats::fail_line(path, lines.number, key + ": " + what);
  };
  while (data.empty()) {
    if (!lines.next(l)) fail("DATA", "missing");
    const auto w = formats::words(l);
    if (w.empty() || w[0][0] == '#') continue;
    const std::string key(w[0]);
    where = path + ":" + std::to_string(lines.number) + ": " + key;
    const std::vector<std::string> rest(w.begin() + 1, w.end());
    if (key == "VERSION") {
      if (rest.size() != 1 || (rest[0] != "0.7" && rest[0] != ".7" && rest[0] != "0.6" && rest[0] != ".6"))
        fail(key, "expected 0.7");
    } else if (key == "FIELDS") {
      fields = rest;
    } else if (key == "SIZE") {
      sizes = rest;
    } else if (key == "TYPE") {
      types = rest;
    } else if (key == "COUNT") {
      counts = rest;
    } else if (key == "WIDTH") {
      if (rest.size() != 1) fail(key, "expected one number");
      cloud.width = number<uint32_t>(rest[0], where);
    } else if (key == "HEIGHT") {
      if (rest.size() != 1) fail(key, "expected one number");
      cloud.height = number<uint32_t>(rest[0], where);
    } else if (key == "VIEWPOINT") {
      if (rest.size() != 7) fail(key, "expected tx ty tz qw qx qy qz");
      double t[3], q[4];
      for (std::size_t i = 0; i < 3; ++i) t[i] = number<double>(rest[i], where);
      for (std::size_t i = 0; i < 4; ++i) q[i] = number<double>(rest[3 + i], where);
      cloud.viewpoint = pose_from(t, q);
    } else if (key == "POINTS") {
      if (rest.size() != 1) fail(key, "expected one number");
      points = number<std::size_t>(rest[0], where);
      have_points = true;
    } else if (key == "DATA") {
      if (rest.size() != 1 || (rest[0] != "ascii" && rest[0] != "binary"))
        fail(key, "expected ascii or binary (binary_compressed is not supported)");
      data = rest[0];
    } else {
      fail(key, "unknown header line");
    }
  }
  if (counts.empty()) counts.assign(fields.size(), "1");
  if (fields.empty() || sizes.size() != fields.size() || types.size() != fields.size() ||
      counts.size() != fields.size())
    fail("FIELDS", "FIELDS, SIZE, TYPE and COUNT must list the same number of entries");
  if (!have_points) points = static_cast<std::size_t>(cloud.width) * cloud.height;
  if (points != static_cast<std::size_t>(cloud.width) * cloud.height) fail("POINTS", "must be WIDTH × HEIGHT");
  // Byte offset (binary) and value index (ascii) of x, y and z in a point.
  std::size_t stride = 0, values = 0;
  std::size_t offset[3] = {0, 0, 0}, index[3] = {0, 0, 0};
  bool found[3] = {false, false, false};
  for (std::size_t f = 0; f < fields.size(); ++f) {
    const std::size_t size = number<std::size_t>(sizes[f], path + ": SIZE");
    const std::size_t count = number<std::size_t>(counts[f], path + ": COUNT");
    for (std::size_t k = 0; k < 3; ++k) {
      if (fields[f] != std::string(1, static_cast<char>('x' + k))) continue;
      if (types[f] != "F" || size != 4 || count != 1) fail("FIELDS", fields[f] + " must be one 4-byte float (F 4 1)");
      offset[k] = stride;
      index[k] = values;
      found[k] = true;
    }
    stride += size * count;
    values += count;
  }
  if (!(found[0] && found[1] && found[2])) fail("FIELDS", "needs x, y and z");
  cloud.points.resize(points);
  const std::size_t pos = lines.pos;
  if (data == "binary") {
    if (text.size() - std::min(pos, text.size()) < points * stride) fail("DATA", "shorter than POINTS × point size");
    for (std::size_t i = 0; i < points; ++i)
      for (std::size_t k = 0; k < 3; ++k)
        std::memcpy(&cloud.points[i][static_cast<Eigen::Index>(k)], text.data() + pos + i * stride + offset[k],
                    sizeof(float));
  } else {
    for (std::size_t i = 0; i < points; ++i) {
      if (!lines.next(l)) fail("DATA", "fewer points than POINTS");
      const auto w = formats::words(l);
      if (w.size() != values) fail("DATA", "expected " + std::to_string(values) + " values");
      for (std::size_t k = 0; k < 3; ++k)
        cloud.points[i][static_cast<Eigen::Index>(k)] =
            number<float>(w[index[k]], path + ":" + std::to_string(lines.number) + ": DATA");
    }
  }
  return cloud;
}

void write_pose(const std::string& path, const Eigen::Isometry3d& T_world_sensor, double time_s) {
  std::string out =
      "# rise-sim: the true pose of the scan's sensor, T_world_sensor (world: z up, m; PCD VIEWPOINT order)\ntime_s ";
  put(out, time_s);
  const Eigen::Vector3d t = T_world_sensor.translation();
  const Eigen::Quaterniond q(T_world_sensor.rotation());
  out += "\nposition_m";
  for (double v : {t.x(), t.y(), t.z()}) {
    out += ' ';
    put(out, v);
  }
  out += "\norientation_wxyz";
  for (double v : {q.w(), q.x(), q.y(), q.z()}) {
    out += ' ';
    put(out, v);
  }
  out += "\nmatrix_row_major";
  const Eigen::Matrix4d M = T_world_sensor.matrix();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      out += ' ';
      put(out, M(r, c));
    }
  out += '\n';
  write_file(path, out);
}

PoseFile read_pose(const std::string& path) {
  const std::string text = formats::read_file(path);
  formats::Lines lines{text};
  PoseFile p;
  double t[3] = {0, 0, 0}, q[4] = {1, 0, 0, 0};
  bool have_t = false, have_q = false;
  for (std::string_view l; lines.next(l);) {
    const auto w = formats::words(l);
    if (w.empty() || w[0][0] == '#') continue;
    const std::string where = path + ":" + std::to_string(lines.number) + ": " + std::string(w[0]);
    const auto expect = [&](std::size_t n) {
      if (w.size() != n + 1) throw std::runtime_error(where + ": expected " + std::to_string(n) + " numbers");
    };
    if (w[0] == "time_s") {
      expect(1);
      p.time_s = number<double>(w[1], where);
    } else if (w[0] == "position_m") {
      expect(3);
      for (std::size_t i = 0; i < 3; ++i) t[i] = number<double>(w[1 + i], where);
      have_t = true;
    } else if (w[0] == "orientation_wxyz") {
      expect(4);
      for (std::size_t i = 0; i < 4; ++i) q[i] = number<double>(w[1 + i], where);
      have_q = true;
    } else if (w[0] != "matrix_row_major") {
      throw std::runtime_error(where + ": unknown key");
    }
  }
  if (!have_t || !have_q) formats::fail_line(path, lines.number, "position_m: missing");
  p.T_world_sensor = pose_from(t, q);
  return p;
}

}  // namespace rise::sim
