#include "semantic/cloud_io.hpp"

// PCL stays inside this file (its headers are heavy): the PCD data is
// decoded by pcl::PCDReader after our own check (formats::check_pcd) has
// given any header error a line number and sized the data against the file.
#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "semantic/cloud_formats.hpp"
#include "semantic/octomap_format.hpp"

namespace rise::semantic {
namespace {

using formats::fail_byte;
using formats::fail_line;
using formats::lower_extension;
using formats::read_file;

bool finite(const Eigen::Vector3f& p) { return p.allFinite(); }

const std::vector<std::string> kExtensions = {".pcd", ".ply", ".xyz", ".3d", ".vtk", ".bt", ".ot"};

[[noreturn]] void unknown_extension(const std::string& path, const std::string& ext) {
  std::string known;
  for (const auto& e : kExtensions) known += (known.empty() ? "" : " ") + e;
  throw std::runtime_error(path + ": unknown extension '" + ext + "' (expected " + known + ")");
}

// An OctoMap's occupied cells as points: 50 M (600 MB) is far above a room
// at 2 cm (freiburg1_360.bt: 0.9 M) and refuses a corrupt or absurd tree.
constexpr uint64_t kMaxOctomapPoints = 50'000'000;

double field_value(const uint8_t* p, uint8_t datatype) {
  switch (datatype) {
    case pcl::PCLPointField::INT8: return static_cast<double>(*reinterpret_cast<const int8_t*>(p));
    case pcl::PCLPointField::UINT8: return static_cast<double>(*p);
    case pcl::PCLPointField::INT16: { int16_t v; std::memcpy(&v, p, 2); return v; }
    case pcl::PCLPointField::UINT16: { uint16_t v; std::memcpy(&v, p, 2); return v; }
    case pcl::PCLPointField::INT32: { int32_t v; std::memcpy(&v, p, 4); return v; }
    case pcl::PCLPointField::UINT32: { uint32_t v; std::memcpy(&v, p, 4); return v; }
    case pcl::PCLPointField::FLOAT32: { float v; std::memcpy(&v, p, 4); return v; }
    case pcl::PCLPointField::FLOAT64: { double v; std::memcpy(&v, p, 8); return v; }
    default: return std::numeric_limits<double>::quiet_NaN();
  }
}

size_t field_size(uint8_t datatype) {
  switch (datatype) {
    case pcl::PCLPointField::INT8: case pcl::PCLPointField::UINT8: return 1;
    case pcl::PCLPointField::INT16: case pcl::PCLPointField::UINT16: return 2;
    case pcl::PCLPointField::FLOAT64: return 8;
    default: return 4;
  }
}

struct PcdRead {
  Cloud cloud;
  Eigen::Isometry3d viewpoint = Eigen::Isometry3d::Identity();
};

PcdRead read_pcd(const std::string& path, std::string_view text) {
  const formats::PcdHeader h = formats::check_pcd(path, text);

  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);  // we report, PCL stays quiet
  pcl::PCLPointCloud2 blob;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int version = 0;
  pcl::PCDReader reader;
  // PCL reads files only, and PCL 1.13's header parser throws or crashes on
  // odd headers (found by tests/fuzz/pcd_fuzz.cpp: std::out_of_range, and a
  // SIGSEGV on repeated FIELDS lines): it gets a temporary file of our
  // canonical header and the file's data bytes.
  static std::atomic<unsigned> serial{0};
  const auto tmp = std::filesystem::temp_directory_path() /
                   ("rise_semantic_" + std::to_string(::getpid()) + "_" + std::to_string(serial++) + ".pcd");
  struct Remove {
    std::filesystem::path p;
    ~Remove() {
      std::error_code ec;
      std::filesystem::remove(p, ec);
    }
  } remove{tmp};
  {
    std::ofstream out(tmp, std::ios::binary);
    const std::string header = formats::canonical_pcd_header(h);
    out.write(header.data(), static_cast<std::streamsize>(header.size()));
    const std::string_view data = text.substr(std::min(h.data_offset, text.size()));
    out.write(data.data(), static_cast<std::streamsize>(data.size()));
    if (!out) throw std::runtime_error(path + ": cannot write the temporary copy " + tmp.string() + ": " + std::strerror(errno));
  }
  int status = -1;
  try {
    status = reader.read(tmp.string(), blob, origin, orientation, version);
  } catch (const std::exception& e) {
    fail_line(path, h.data_line, "DATA " + h.data + ": PCL's PCDReader failed: " + e.what());
  }
  if (status < 0) fail_line(path, h.data_line, "DATA " + h.data + ": PCL's PCDReader refused the data");

  const auto find = [&](const char* name) -> const pcl::PCLPointField* {
    for (const auto& f : blob.fields)
      if (f.name == name) return &f;
    return nullptr;
  };
  const pcl::PCLPointField* xyz[3] = {find("x"), find("y"), find("z")};
  const pcl::PCLPointField* nxyz[3] = {find("normal_x"), find("normal_y"), find("normal_z")};
  const bool normals = nxyz[0] && nxyz[1] && nxyz[2];
  const uint64_t n = static_cast<uint64_t>(blob.width) * blob.height;
  const auto inside = [&](const pcl::PCLPointField* f) {
    return f != nullptr && f->offset + field_size(f->datatype) <= blob.point_step;
  };
  for (auto* f : xyz)
    if (!inside(f)) fail_line(path, h.data_line, "FIELDS: x y z not readable");
  for (auto* f : nxyz)
    if (normals && !inside(f)) fail_line(path, h.data_line, "FIELDS: normals not readable");
  if (blob.data.size() < n * blob.point_step) fail_byte(path, text.size(), "data shorter than announced");

  PcdRead out;
  out.cloud.points.reserve(n);
  if (normals) out.cloud.normals.reserve(n);
  for (uint64_t i = 0; i < n; ++i) {
    const uint8_t* p = blob.data.data() + i * blob.point_step;
    const Eigen::Vector3f q(static_cast<float>(field_value(p + xyz[0]->offset, xyz[0]->datatype)),
                            static_cast<float>(field_value(p + xyz[1]->offset, xyz[1]->datatype)),
                            static_cast<float>(field_value(p + xyz[2]->offset, xyz[2]->datatype)));
    if (!finite(q)) continue;  // organised clouds mark missing returns with NaN
    out.cloud.points.push_back(q);
    if (normals) {
      Eigen::Vector3f m(static_cast<float>(field_value(p + nxyz[0]->offset, nxyz[0]->datatype)),
                        static_cast<float>(field_value(p + nxyz[1]->offset, nxyz[1]->datatype)),
                        static_cast<float>(field_value(p + nxyz[2]->offset, nxyz[2]->datatype)));
      const float len = m.norm();
      out.cloud.normals.push_back(std::isfinite(len) && len > 0.0f ? Eigen::Vector3f(m / len) : Eigen::Vector3f::Zero());
    }
  }
  out.viewpoint.linear() = orientation.cast<double>().normalized().toRotationMatrix();
  out.viewpoint.translation() = origin.head<3>().cast<double>();
  if (!out.viewpoint.matrix().allFinite()) out.viewpoint = Eigen::Isometry3d::Identity();
  return out;
}

}  // namespace

Eigen::Isometry3d read_3dtk_pose(const std::string& path) { return formats::parse_3dtk_pose(path, read_file(path)); }

std::vector<Eigen::Isometry3d> read_3dtk_frames(const std::string& path) {
  return formats::parse_3dtk_frames(path, read_file(path));
}

Cloud read_cloud(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (std::find(kExtensions.begin(), kExtensions.end(), ext) == kExtensions.end()) unknown_extension(path, ext);
  return parse_cloud(path, read_file(path));
}

Cloud parse_cloud(const std::string& path, const std::string& contents) {
  const std::string ext = lower_extension(path);
  if (ext == ".pcd") return read_pcd(path, contents).cloud;
  if (ext == ".ply") return formats::parse_ply(path, contents);
  if (ext == ".xyz") return formats::parse_xyz(path, contents);
  if (ext == ".3d") return formats::parse_3d(path, contents);
  if (ext == ".vtk") return formats::parse_vtk(path, contents);
  if (ext == ".bt" || ext == ".ot") return formats::octomap_cloud(path, contents, kMaxOctomapPoints);
  unknown_extension(path, ext);
}

Scan read_scan(const std::string& path) {
  Scan scan;
  const std::filesystem::path p(path);
  scan.name = p.stem().string();
  const std::string ext = lower_extension(path);
  const std::filesystem::path pose = std::filesystem::path(p).replace_extension(".pose");
  if (ext == ".pcd") {
    const std::string text = read_file(path);
    PcdRead r = read_pcd(path, text);
    scan.cloud = std::move(r.cloud);
    if (std::filesystem::exists(pose))
      scan.T_world_scan = formats::parse_sim_pose(pose.string(), read_file(pose.string()));
    else if (!r.viewpoint.isApprox(Eigen::Isometry3d::Identity()))
      scan.T_world_scan = r.viewpoint;
  } else {
    scan.cloud = read_cloud(path);
    if (ext == ".3d") {
      if (std::filesystem::exists(pose)) scan.T_world_scan = read_3dtk_pose(pose.string());
      const std::filesystem::path config = p.parent_path() / "config.ini";
      if (std::filesystem::exists(config)) {
        const auto range = formats::parse_3dtk_config(config.string(), read_file(config.string()));
        std::erase_if(scan.cloud.points, [&](const Eigen::Vector3f& q) {
          const double r = q.norm();
          return r < range.min_m || (range.max_m > 0.0 && r >= range.max_m);
        });
      }
    }
  }
  return scan;
}

void write_cloud(const std::string& path, const Cloud& cloud) {
  const std::string ext = lower_extension(path);
  const bool normals = cloud.normals.size() == cloud.points.size() && !cloud.normals.empty();
  std::ostringstream out;
  const auto put = [&](float v) {
    uint32_t u;
    std::memcpy(&u, &v, 4);
    if constexpr (std::endian::native == std::endian::big) u = __builtin_bswap32(u);
    out.write(reinterpret_cast<const char*>(&u), 4);
  };
  if (ext == ".pcd") {
    out << "# .PCD v0.7 - Point Cloud Data file format (rise::semantic)\nVERSION 0.7\n";
    if (normals)
      out << "FIELDS x y z normal_x normal_y normal_z\nSIZE 4 4 4 4 4 4\nTYPE F F F F F F\nCOUNT 1 1 1 1 1 1\n";
    else
      out << "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
    out << "WIDTH " << cloud.size() << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << cloud.size()
        << "\nDATA binary\n";
  } else if (ext == ".ply") {
    out << "ply\nformat binary_little_endian 1.0\ncomment rise::semantic\nelement vertex " << cloud.size()
        << "\nproperty float x\nproperty float y\nproperty float z\n";
    if (normals) out << "property float nx\nproperty float ny\nproperty float nz\n";
    out << "end_header\n";
  } else if (ext == ".xyz") {
    out.precision(9);
    for (size_t i = 0; i < cloud.size(); ++i) {
      const auto& p = cloud.points[i];
      out << p.x() << ' ' << p.y() << ' ' << p.z();
      if (normals) out << ' ' << cloud.normals[i].x() << ' ' << cloud.normals[i].y() << ' ' << cloud.normals[i].z();
      out << '\n';
    }
  } else {
    throw std::runtime_error(path + ": cannot write '" + ext + "' (expected .pcd .ply .xyz)");
  }
  if (ext != ".xyz")
    for (size_t i = 0; i < cloud.size(); ++i) {
      for (int k = 0; k < 3; ++k) put(cloud.points[i][k]);
      if (normals)
        for (int k = 0; k < 3; ++k) put(cloud.normals[i][k]);
    }
  std::ofstream f(path, std::ios::binary);
  const std::string s = std::move(out).str();
  f.write(s.data(), static_cast<std::streamsize>(s.size()));
  if (!f) throw std::runtime_error(path + ": cannot write: " + std::strerror(errno));
}

}  // namespace rise::semantic
