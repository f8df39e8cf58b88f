#include "semantic/cloud_formats.hpp"
#include "semantic/cloud_io.hpp"

#include <catch2/catch.hpp>

#include "tests/test_data.hpp"

#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

namespace sem = rise::semantic;
namespace fs = std::filesystem;

namespace {

using rise::test::data_file;

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("rise_cloud_io_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

void write(const fs::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

sem::Cloud random_cloud(size_t n, bool normals) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-5.0f, 5.0f);
  sem::Cloud c;
  for (size_t i = 0; i < n; ++i) {
    c.points.emplace_back(u(rng), u(rng), u(rng));
    if (normals) c.normals.push_back(Eigen::Vector3f(u(rng), u(rng), u(rng)).normalized());
  }
  return c;
}

std::string error_of(const std::string& path, const std::string& bytes) {
  try {
    (void)sem::parse_cloud(path, bytes);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST_CASE("PCD reader reads every PCL test cloud with its point count", "[semantic]") {
  // Counts from the data's MANIFEST.md (finite points of the organised ones).
  const auto [file, points, normals] = GENERATE(table<std::string, size_t, bool>({
      {"bun0.pcd", 397, true},
      {"bun01.pcd", 200, false},
      {"bun02.pcd", 217, false},
      {"bun03.pcd", 197, false},
      {"bun4.pcd", 361, false},
      {"bunny.pcd", 397, false},
      {"office1.pcd", 254456, false},
      {"sac_plane_test.pcd", 3283, true},
      {"table_scene_mug_stereo_textured.pcd", 209280, false},
  }));
  const std::string path = data_file("pointclouds/pcl/" + file);
  if (path.empty()) {
    WARN("skipped: RISE_TEST_DATA/pointclouds/pcl/" << file << " not found");
    return;
  }
  const sem::Cloud c = sem::read_cloud(path);
  CHECK(c.size() == points);
  CHECK(c.normals.size() == (normals ? points : 0));
  for (const auto& p : c.points) REQUIRE(p.allFinite());
  if (file == "office1.pcd") {
    // ~4 x 3.8 x 3.5 m (MANIFEST.md).
    Eigen::Vector3f lo = c.points[0], hi = c.points[0];
    for (const auto& p : c.points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    const Eigen::Vector3f e = hi - lo;
    CHECK(e.maxCoeff() < 6.0f);
    CHECK(e.minCoeff() > 2.0f);
  }
}

TEST_CASE("PCD binary written by write_cloud reads back through PCL bit for bit", "[semantic]") {
  const bool normals = GENERATE(false, true);
  const sem::Cloud c = random_cloud(1000, normals);
  const auto p = scratch(normals ? "n.pcd" : "p.pcd").string();
  sem::write_cloud(p, c);
  const sem::Cloud r = sem::read_cloud(p);
  REQUIRE(r.size() == c.size());
  CHECK(r.points == c.points);
  CHECK(r.normals.size() == (normals ? c.size() : 0));
}

TEST_CASE("PLY round trip in ascii, binary little and big endian", "[semantic]") {
  const sem::Cloud c = random_cloud(200, true);
  SECTION("binary little endian, as write_cloud writes it") {
    const auto p = scratch("le.ply").string();
    sem::write_cloud(p, c);
    const sem::Cloud r = sem::read_cloud(p);
    CHECK(r.points == c.points);
    REQUIRE(r.normals.size() == c.size());
    for (size_t i = 0; i < c.size(); ++i) CHECK((r.normals[i] - c.normals[i]).norm() < 1e-6f);
  }
  SECTION("ascii and big endian with a face element and extra properties") {
    std::string ascii = "ply\nformat ascii 1.0\ncomment test\nelement vertex 3\nproperty float x\nproperty float y\n"
                        "property float z\nproperty uchar red\nelement face 1\nproperty list uchar int vertex_indices\n"
                        "end_header\n";
    ascii += "1 2 3 255\n-1.5 0.25 4e2 0\n0 0 0 7\n3 0 1 2\n";
    const sem::Cloud a = sem::parse_cloud("a.ply", ascii);
    REQUIRE(a.size() == 3);
    CHECK(a.points[1] == Eigen::Vector3f(-1.5f, 0.25f, 400.0f));
    CHECK(a.normals.empty());

    // The same vertices as big-endian doubles, a face before the vertices.
    std::string big = "ply\nformat binary_big_endian 1.0\nelement face 1\nproperty list uchar int vertex_indices\n"
                      "element vertex 2\nproperty double x\nproperty double y\nproperty double z\nend_header\n";
    big += std::string("\x03\x00\x00\x00\x00\x00\x00\x00\x01\x00\x00\x00\x02", 13);
    for (double v : {1.0, 2.0, 3.0, -1.5, 0.25, 400.0}) {
      uint64_t u;
      std::memcpy(&u, &v, 8);
      for (int s = 56; s >= 0; s -= 8) big.push_back(static_cast<char>((u >> s) & 0xFF));
    }
    const sem::Cloud b = sem::parse_cloud("b.ply", big);
    REQUIRE(b.size() == 2);
    CHECK(b.points[0] == Eigen::Vector3f(1, 2, 3));
    CHECK(b.points[1] == Eigen::Vector3f(-1.5f, 0.25f, 400.0f));
  }
}

TEST_CASE("XYZ text round trip with and without normals", "[semantic]") {
  const bool normals = GENERATE(false, true);
  const sem::Cloud c = random_cloud(100, normals);
  const auto p = scratch("c.xyz").string();
  sem::write_cloud(p, c);
  const sem::Cloud r = sem::read_cloud(p);
  CHECK(r.points == c.points);  // 9 significant digits: exact for float
  CHECK(r.normals.size() == c.normals.size());
}

TEST_CASE("3DTK scans read in metres, right-handed, z up, with their odometry poses", "[semantic]") {
  const std::string path = data_file("pointclouds/3DTK-dat/scan001.3d");
  if (path.empty()) {
    WARN("skipped: RISE_TEST_DATA/pointclouds/3DTK-dat not found");
    return;
  }
  const sem::Scan s = sem::read_scan(path);
  CHECK(s.name == "scan001");
  // 81360 lines "x y z": the first is a point too (3DTK skips only a "W x H" header).
  const sem::Cloud all = sem::read_cloud(path);
  CHECK(all.size() == 81360);
  // As a scan, config.ini's range limits apply (min=48, max=3276 cm): the
  // points its scanner wrote at 32.76 m for no return are gone.
  size_t in_range = 0;
  for (const auto& p : all.points) in_range += p.norm() >= 0.48f && p.norm() < 32.76f ? 1 : 0;
  CHECK(in_range < 81360 - 1000);
  CHECK(s.cloud.size() == in_range);
  REQUIRE(s.T_world_scan.has_value());
  // scan001.pose: -3.10605 -7.50803 156.917 cm (x right, y up, z forward):
  // 1.569 m forward, 3.1 cm to the left, 7.5 cm down.
  const Eigen::Vector3d t = s.T_world_scan->translation();
  CHECK(t.x() == Approx(1.56917).margin(1e-6));
  CHECK(t.y() == Approx(0.0310605).margin(1e-6));
  CHECK(t.z() == Approx(-0.0750803).margin(1e-6));
  // Their forward z (0 .. 3276 cm) is our x; their up y (-7.5 .. 24.6 m) our z.
  Eigen::Vector3f lo = s.cloud.points[0], hi = s.cloud.points[0];
  for (const auto& p : s.cloud.points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  CHECK(lo.x() > -0.01f);
  CHECK(hi.x() < 32.8f);
  CHECK(lo.z() > -8.0f);
  CHECK(hi.z() < 25.0f);
  // A point 1 m to their right (x = 100 cm) is 1 m to our right: y = -1.
  const sem::Cloud one = sem::parse_cloud("one.3d", "100 0 0\n");
  REQUIRE(one.size() == 1);
  CHECK((one.points[0] - Eigen::Vector3f(0.0f, -1.0f, 0.0f)).norm() < 1e-6f);

  // The odometry pose and slam6d's first frame of the same scan agree: both
  // read through the same Euler convention (Rx·Ry·Rz, OpenGL column-major).
  const auto frames = sem::read_3dtk_frames(data_file("pointclouds/3DTK-dat/scan001.frames"));
  REQUIRE(frames.size() == 3);
  const Eigen::Isometry3d last = frames.back();
  CHECK(last.translation().x() == Approx(1.56796).margin(1e-6));
  CHECK(last.translation().y() == Approx(0.036331).margin(1e-6));
  CHECK(last.translation().z() == Approx(-0.0908315).margin(1e-6));
  CHECK(Eigen::AngleAxisd(last.linear().transpose() * s.T_world_scan->linear()).angle() < 0.02);
  CHECK(last.linear().determinant() == Approx(1.0).margin(1e-9));
}

TEST_CASE("3DTK Euler angles follow slam6d's EulerToMatrix4", "[semantic]") {
  // EulerToMatrix4 column-major: [0] = cy cz, [1] = sx sy cz + cx sz, [8] = sy, [9] = -sx cy.
  const double x = 0.3, y = -0.2, z = 0.5;
  const Eigen::Matrix3d R = sem::euler_3dtk({0, 0, 0}, {x, y, z}).linear();
  CHECK(R(0, 0) == Approx(std::cos(y) * std::cos(z)));
  CHECK(R(1, 0) == Approx(std::sin(x) * std::sin(y) * std::cos(z) + std::cos(x) * std::sin(z)));
  CHECK(R(0, 2) == Approx(std::sin(y)));
  CHECK(R(1, 2) == Approx(-std::sin(x) * std::cos(y)));
  // Ours from theirs: a point 1 m forward (their z) is our +x.
  CHECK(sem::from_3dtk_point({0, 0, 100}).isApprox(Eigen::Vector3f(1, 0, 0)));
  CHECK(sem::from_3dtk_point({0, 100, 0}).isApprox(Eigen::Vector3f(0, 0, 1)));
  CHECK(sem::from_3dtk_point({100, 0, 0}).isApprox(Eigen::Vector3f(0, -1, 0)));
}

TEST_CASE("simulator scans read their true pose from the .pose beside the PCD", "[semantic]") {
  const auto pcd = scratch("scan_0001.pcd");
  sem::write_cloud(pcd.string(), random_cloud(10, false));
  write(scratch("scan_0001.pose"),
        "# rise-sim: the true pose\ntime_s 1\nposition_m 0.25 -1 0.5\norientation_wxyz 0.7071067811865476 0 0 "
        "0.7071067811865476\nmatrix_row_major 0 -1 0 0.25 1 0 0 -1 0 0 1 0.5 0 0 0 1\n");
  const sem::Scan s = sem::read_scan(pcd.string());
  REQUIRE(s.T_world_scan.has_value());
  CHECK(s.T_world_scan->translation().isApprox(Eigen::Vector3d(0.25, -1, 0.5)));
  CHECK((s.T_world_scan->linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY()));
  CHECK(s.cloud.size() == 10);

  write(scratch("scan_0001.pose"), "time_s 1\nposition_m 0.25 -1\n");
  CHECK_THROWS_WITH(sem::read_scan(pcd.string()), Catch::Contains("scan_0001.pose:2: position_m"));
}

TEST_CASE("bad files are refused with the file and the line or byte offset", "[semantic]") {
  const std::string pcd_head = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\n"
                               "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\n";
  SECTION("PCD") {
    CHECK_THAT(error_of("t.pcd", pcd_head + "DATA binary\n" + std::string(20, '\0')),
               Catch::Contains("t.pcd: byte 141: binary data truncated: 2 points need 24 bytes, 20 left"));
    CHECK_THAT(error_of("t.pcd", pcd_head + "DATA ascii\n1 2 3\n4 5\n"),
               Catch::Contains("t.pcd:12: expected 3 values, found 2"));
    CHECK_THAT(error_of("t.pcd", pcd_head + "DATA ascii\n1 2 3\n"), Catch::Contains("t.pcd:11: ascii data: 1 points, 2 announced"));
    CHECK_THAT(error_of("t.pcd", "VERSION 0.7\nFIELDS x y z\nSIZE 4 4\nTYPE F F F\nDATA ascii\n"),
               Catch::Contains("t.pcd:3: SIZE: one per field expected"));
    CHECK_THAT(error_of("t.pcd", "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH two\n"),
               Catch::Contains("t.pcd:5: WIDTH: not a number: 'two'"));
    CHECK_THAT(error_of("t.pcd", "VERSION 0.7\nFRUITS x y z\n"), Catch::Contains("t.pcd:2: unknown header key 'FRUITS'"));
    CHECK_THAT(error_of("t.pcd", pcd_head + "DATA binary_compressed\n" + std::string("\x10\x00\x00\x00\x18\x00\x00\x00", 8)),
               Catch::Contains("t.pcd: byte 140: binary_compressed data truncated: 16 bytes announced, 0 left"));
    // Found by the fuzzer (PCL's reader crashed on repeated keys): refused by our check.
    CHECK_THAT(error_of("t.pcd", "VERSION 0.7\nFIELDS x y z\nFIELDS x y z normal_x\n"),
               Catch::Contains("t.pcd:3: FIELDS: given twice (first on line 2)"));
    CHECK_THAT(error_of("t.pcd", "VERSION 0.7\nFIELDS x y z\xfe\n"), Catch::Contains("t.pcd:2: FIELDS: field name"));
    // Found by the fuzzer: PCL takes binary data that starts with a header keyword for the header.
    CHECK_THAT(error_of("t.pcd", pcd_head + "DATA binary\nCOLUMNS?" + std::string(16, '\0')),
               Catch::Contains("t.pcd: byte 121: binary data has a line beginning with 'COLUMNS'"));
    // Found by the fuzzer: PCL skips '#' comment lines and blank lines before
    // it looks for a keyword, then allocates what a POINTS line says.
    CHECK_THAT(error_of("t.pcd", pcd_head + "DATA binary\n# comment\n\n  POINTS 99999999999\n" + std::string(16, '\0')),
               Catch::Contains("t.pcd: byte 132: binary data has a line beginning with 'POINTS'"));
    // Found by the fuzzer: ascii data without POINTS or WIDTH whose first line
    // starts with a keyword; PCL read it as a header line and allocated ~100 TB.
    CHECK_THAT(error_of("t.pcd", "VERSION .5\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n\nDATA ascii\nCOUNT0.01349 0.0407" +
                                     std::string(5, '\0') + "0 0.086298 " + std::string(11, '\0') + "337\n"),
               Catch::Contains("t.pcd: byte 58: ascii data has a line beginning with 'COUNT'"));
    // Found by the fuzzer: PCL's ascii reader sizes its buffers by a point's
    // values, with no points at all: 41 GB for this COUNT.
    CHECK_THAT(error_of("t.pcd", "# .PCD v.5\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1297379212\nDATA ascii\n"
                                 "82 39795\n"),
               Catch::Contains("t.pcd:5: COUNT: 1297379212 values in one field, more than 65536"));
    // 1.2 GB announced by a 4-byte LZF block: refused before PCL allocates.
    const std::string huge = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 100000000\nHEIGHT 1\n"
                             "POINTS 100000000\nDATA binary_compressed\n";
    CHECK_THAT(error_of("t.pcd", huge + std::string("\x04\x00\x00\x00\x00\x8c\x86\x47", 8) + "abcd"),
               Catch::Contains("uncompressed bytes cannot come from 4"));
    // Found by the fuzzer: PCL's own header reader throws std::out_of_range on this one.
    CHECK_THAT(error_of("t.pcd", pcd_head + "DATA binary\n" + std::string("\x44\x41\x54\x41\x00\x00\x00\x40\x00\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff\x00\x40\x00\x00\x40\xc0\x7f\x00\x00\x00\x00\x00\x00\x00\x00", 43)),
               Catch::Contains("t.pcd: byte 121: binary data has a line beginning with 'DATA'"));
    CHECK_THAT(error_of("t.pcd", "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 3\nHEIGHT 1\nPOINTS 2\nDATA ascii\n"),
               Catch::Contains("t.pcd:7: POINTS: 2 is not WIDTH x HEIGHT = 3"));
  }
  SECTION("PLY") {
    const std::string head = "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                             "property float z\nend_header\n";
    CHECK_THAT(error_of("t.ply", head + std::string(16, '\0')), Catch::Contains("t.ply: byte 131: binary data truncated"));
    CHECK_THAT(error_of("t.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                                 "property float z\nend_header\n1 2 3\n4 5\n"),
               Catch::Contains("t.ply:9: element vertex: too few values for 'z'"));
    CHECK_THAT(error_of("t.ply", "ply\nformat ascii 1.0\nelement vertex 99999999\nproperty float x\nproperty float y\n"
                                 "property float z\nend_header\n1 2 3\n"),
               Catch::Contains("t.ply:7: element vertex: count 99999999 exceeds"));
    CHECK_THAT(error_of("t.ply", "ply\nformat ascii 2.0\n"), Catch::Contains("t.ply:2: format"));
    CHECK_THAT(error_of("t.ply", "plx\n"), Catch::Contains("t.ply:1: not a PLY file"));
    CHECK_THAT(error_of("t.ply", "ply\nformat ascii 1.0\nproperty float x\n"), Catch::Contains("t.ply:3: property: before any element"));
    CHECK_THAT(error_of("t.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n"),
               Catch::Contains("t.ply:5: element vertex: no x y z"));
  }
  SECTION("XYZ and 3DTK") {
    CHECK_THAT(error_of("t.xyz", "1 2 3\n4 5 x\n"), Catch::Contains("t.xyz:2: z: not a number: 'x'"));
    CHECK_THAT(error_of("t.xyz", "1 2 3\n4 5 6 7 8 9\n"), Catch::Contains("t.xyz:2: expected 3 values"));
    CHECK_THAT(error_of("t.3d", "360 x 225\n1 2 3\n4 5\n"), Catch::Contains("t.3d:3: expected 'x y z' (cm)"));
    CHECK(sem::parse_cloud("t.3d", "360 x 225\n1 2 3\n").size() == 1);
    const auto frames = scratch("bad.frames");
    write(frames, "1 0 0 0 0 1 0 0 0 0 1 0 5 6 7 1 1\n1 0 0\n");
    CHECK_THROWS_WITH(sem::read_3dtk_frames(frames.string()), Catch::Contains("bad.frames:2: expected 16 matrix entries"));
  }
  SECTION("missing files and unknown extensions") {
    CHECK_THROWS_WITH(sem::read_cloud("/nonexistent/x.pcd"), "/nonexistent/x.pcd: cannot open: No such file or directory");
    CHECK_THROWS_WITH(sem::read_cloud("x.obj"), Catch::StartsWith("x.obj: unknown extension"));
  }
}

TEST_CASE("3DTK's config.ini gives the range limits and names the line of a bad one", "[semantic]") {
  using sem::formats::parse_3dtk_config;
  const auto r = parse_3dtk_config("config.ini", "max=3276 # maximum point distance\nmin=48   # minimum\nadvanced=true\n");
  CHECK(r.max_m == Approx(32.76));
  CHECK(r.min_m == Approx(0.48));
  CHECK(parse_3dtk_config("c.ini", "").max_m == 0.0);  // no limits
  const auto message = [](const std::string& text) {
    try {
      (void)parse_3dtk_config("c.ini", text);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK(message("min=1\nmax=far\n") == "c.ini:2: max: not a number: 'far'");
  CHECK(message("max=-5\n") == "c.ini:1: max: must be a distance >= 0 (cm)");
  CHECK(message("max\n") == "c.ini:1: max: expected key=value");
  CHECK(message("min=50\nmax=40\n").find("min must be below max") != std::string::npos);
}
