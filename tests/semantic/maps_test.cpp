// The 3D map readers against the formats' own libraries: our OctoMap reader
// against liboctomap (which reads freiburg1_360.bt and writes the .ot files
// we read back), our legacy VTK reader against VTK's writers and PCL's.
// Only this test includes those libraries; rise::semantic does not.
#include "semantic/octomap_format.hpp"

#include <catch2/catch.hpp>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>
#include <octomap/OcTreeStamped.h>
#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <pcl/io/vtk_io.h>
#include <pcl/point_types.h>
#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataWriter.h>
#include <vtkStructuredGrid.h>
#include <vtkStructuredGridWriter.h>
#include <vtkUnstructuredGrid.h>
#include <vtkUnstructuredGridWriter.h>

#include "semantic/cloud_formats.hpp"
#include "semantic/cloud_io.hpp"
#include "tests/test_data.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <iterator>
#include <random>
#include <tuple>

namespace sem = rise::semantic;
namespace fs = std::filesystem;

namespace {

using rise::test::data_file;

// A folder of this run's files, removed when the program ends.
fs::path scratch(const std::string& name) {
  static const struct Dir {
    fs::path path = fs::temp_directory_path() / ("rise_maps_test_" + std::to_string(::getpid()));
    Dir() { fs::create_directories(path); }
    ~Dir() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  } dir;
  return dir.path / name;
}

std::string error_of(const std::string& path, const std::string& bytes) {
  try {
    (void)sem::parse_cloud(path, bytes);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

// A leaf as integers: depth, its centre in half cells, occupied, and its
// log-odds (NaN when the file has none): exact to compare, and sortable.
using LeafKey = std::tuple<int, long, long, long, bool, float>;

LeafKey key_of(int depth, double x, double y, double z, double res, bool occupied, float log_odds) {
  return {depth, std::lround(2 * x / res), std::lround(2 * y / res), std::lround(2 * z / res), occupied, log_odds};
}

std::vector<LeafKey> ours(const sem::OctoMap& map) {
  std::vector<LeafKey> v;
  for (const auto& l : map.leaves)
    v.push_back(key_of(l.depth, l.centre_m.x(), l.centre_m.y(), l.centre_m.z(), map.resolution_m, l.occupied,
                       l.log_odds.value_or(NAN)));
  std::sort(v.begin(), v.end());
  return v;
}

template <typename Tree>
std::vector<LeafKey> theirs(const Tree& tree, bool with_log_odds) {
  std::vector<LeafKey> v;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it)
    v.push_back(key_of(static_cast<int>(it.getDepth()), it.getX(), it.getY(), it.getZ(), tree.getResolution(),
                       tree.isNodeOccupied(*it), with_log_odds ? it->getLogOdds() : NAN));
  std::sort(v.begin(), v.end());
  return v;
}

// NaN != NaN: compare the .bt leaves (no log-odds) on the other fields.
bool same_leaves(const std::vector<LeafKey>& a, const std::vector<LeafKey>& b) {
  const auto eq = [](const LeafKey& x, const LeafKey& y) {
    return std::get<0>(x) == std::get<0>(y) && std::get<1>(x) == std::get<1>(y) && std::get<2>(x) == std::get<2>(y) &&
           std::get<3>(x) == std::get<3>(y) && std::get<4>(x) == std::get<4>(y) &&
           (std::get<5>(x) == std::get<5>(y) || (std::isnan(std::get<5>(x)) && std::isnan(std::get<5>(y))));
  };
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), eq);
}

const std::string kBtHeader = "# Octomap OcTree binary file\nid OcTree\nsize 3\nres 0.1\ndata\n";

}  // namespace

TEST_CASE("OctoMap .bt reader counts freiburg1_360.bt's nodes and leaves as octomap does", "[semantic]") {
  const std::string path = data_file("pointclouds/ANYbotics_grid_map/freiburg1_360.bt");
  if (path.empty()) {
    WARN("skipped: RISE_TEST_DATA/pointclouds/ANYbotics_grid_map/freiburg1_360.bt not found");
    return;
  }
  const sem::OctoMap map = sem::read_octomap(path);
  CHECK(map.tree_type == "ColorOcTree");  // its binary stream is occupancy only
  CHECK(map.resolution_m == 0.02);
  // Counted by us and by liboctomap 1.9.7 (below). MANIFEST.md has the
  // occupied and free counts the other way round; octomap's own
  // isNodeOccupied agrees with these.
  CHECK(map.nodes == 1547112);
  CHECK(map.inner_nodes == 270231);
  const auto occupied = std::count_if(map.leaves.begin(), map.leaves.end(), [](const auto& l) { return l.occupied; });
  CHECK(occupied == 563449);
  CHECK(map.leaves.size() - static_cast<size_t>(occupied) == 713432);
  // Occupied leaves by depth: 725 of 8 cm, 58606 of 4 cm, the rest of 2 cm.
  CHECK(map.occupied_cells == 504118 + 58606 * 8 + 725 * 64);

  // The occupied cubes' bounding box (octomap's getMetricMin/Max, -3.78 ..
  // 3.52, -4.74 .. 3.16, -0.24 .. 4.32, also spans the free leaves).
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = -lo;
  for (const auto& l : map.leaves)
    if (l.occupied) {
      lo = lo.cwiseMin(l.centre_m - Eigen::Vector3d::Constant(l.size_m / 2));
      hi = hi.cwiseMax(l.centre_m + Eigen::Vector3d::Constant(l.size_m / 2));
    }
  CHECK(lo.isApprox(Eigen::Vector3d(-3.72, -4.44, -0.24), 1e-9));
  CHECK(hi.isApprox(Eigen::Vector3d(3.36, 3.16, 4.20), 1e-9));

  // The cloud: one point per occupied 2 cm cell.
  const sem::Cloud cloud = sem::read_cloud(path);
  CHECK(cloud.size() == map.occupied_cells);
  Eigen::Vector3f cmin = Eigen::Vector3f::Constant(1e9f), cmax = -cmin;
  for (const auto& p : cloud.points) cmin = cmin.cwiseMin(p), cmax = cmax.cwiseMax(p);
  CHECK(cmin.isApprox(Eigen::Vector3f(-3.71f, -4.43f, -0.23f), 1e-5f));
  CHECK(cmax.isApprox(Eigen::Vector3f(3.35f, 3.15f, 4.19f), 1e-5f));

  // liboctomap's own reading: the same counts, box and leaves.
  octomap::OcTree tree(0.1);
  REQUIRE(tree.readBinary(path));
  CHECK(tree.size() == map.nodes);
  CHECK(tree.getNumLeafNodes() == map.leaves.size());
  CHECK(tree.getResolution() == map.resolution_m);
  const auto expected = theirs(tree, false);
  CHECK(same_leaves(ours(map), expected));

  SECTION("the same tree as a full .ot written by octomap reads to the same leaves, with log-odds") {
    const auto ot = scratch("freiburg1_360.ot");
    REQUIRE(tree.write(ot.string()));
    const sem::OctoMap full = sem::read_octomap(ot.string());
    CHECK(full.tree_type == "OcTree");
    CHECK(full.nodes == map.nodes);
    CHECK(full.inner_nodes == map.inner_nodes);
    CHECK(same_leaves(ours(full), theirs(tree, true)));
    // Max-likelihood leaves: log-odds at octomap's clamping bounds.
    const auto clamped = std::count_if(full.leaves.begin(), full.leaves.end(), [&](const auto& l) {
      return *l.log_odds == (l.occupied ? tree.getClampingThresMaxLog() : tree.getClampingThresMinLog());
    });
    CHECK(static_cast<size_t>(clamped) == full.leaves.size());
    CHECK(sem::read_cloud(ot.string()).size() == cloud.size());
  }
}

TEST_CASE("OctoMap .ot reader reads octomap's OcTree, ColorOcTree and OcTreeStamped with their log-odds", "[semantic]") {
  // Leaves of every kind: measured hits and misses (log-odds around the
  // threshold), eight equal siblings pruned into a coarser leaf, and
  // points far from the origin on both sides.
  const auto fill = [](auto& tree) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-3.0f, 3.0f);
    std::uniform_int_distribution<int> hits(-3, 4);
    for (int i = 0; i < 500; ++i) {
      const octomap::point3d p(u(rng), u(rng), u(rng) * 0.5f);
      for (int h = hits(rng); h != 0; h += h > 0 ? -1 : 1) tree.updateNode(p, h > 0);
    }
    // A 0.4 m cube of cells on the key grid (10, -20 and 0 m are multiples of 0.4 m).
    const double res = tree.getResolution();
    const int k = static_cast<int>(std::lround(0.4 / res));
    for (int x = 0; x < k; ++x)
      for (int y = 0; y < k; ++y)
        for (int z = 0; z < k; ++z)
          tree.updateNode(octomap::point3d(static_cast<float>(10.0 + (x + 0.5) * res), static_cast<float>(-20.0 + (y + 0.5) * res),
                                           static_cast<float>((z + 0.5) * res)),
                          true);
    tree.updateInnerOccupancy();
    tree.prune();
  };
  const auto check = [](const auto& tree, const std::string& file, const std::string& id) {
    REQUIRE(tree.write(file));
    const sem::OctoMap map = sem::read_octomap(file);
    CHECK(map.tree_type == id);
    CHECK(map.nodes == tree.size());
    CHECK(map.leaves.size() == tree.getNumLeafNodes());
    CHECK(same_leaves(ours(map), theirs(tree, true)));
    // OcTreeStamped prunes only siblings stamped in the same second.
    const auto coarse = std::count_if(map.leaves.begin(), map.leaves.end(), [](const auto& l) { return l.depth < 16; });
    if (id != "OcTreeStamped") CHECK(coarse > 0);
    size_t occupied = 0;
    for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it)
      if (tree.isNodeOccupied(*it)) occupied += size_t{1} << (3 * (16 - it.getDepth()));
    CHECK(map.occupied_cells == occupied);
    CHECK(sem::read_cloud(file).size() == occupied);
  };
  SECTION("OcTree") {
    octomap::OcTree tree(0.1);
    fill(tree);
    check(tree, scratch("t.ot").string(), "OcTree");
  }
  SECTION("ColorOcTree: log-odds then r g b per node") {
    octomap::ColorOcTree tree(0.05);
    fill(tree);
    uint8_t c = 0;
    for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it, c += 37) it->setColor(c, 255 - c, c / 2);
    tree.updateInnerOccupancy();  // also the inner nodes' average colours
    check(tree, scratch("color.ot").string(), "ColorOcTree");
  }
  SECTION("OcTreeStamped: its timestamp is not in the file") {
    octomap::OcTreeStamped tree(0.2);
    fill(tree);
    check(tree, scratch("stamped.ot").string(), "OcTreeStamped");
  }
}

TEST_CASE("OctoMap .ot reader takes a root without children as one leaf over the whole tree, as octomap does", "[semantic]") {
  // fuzz_maps found it (the harness took depth 0 for an error): a tree
  // pruned to its root, occupied (log-odds 3.5), colour 1 2 3.
  const std::string bytes("# Octomap OcTree file\nid ColorOcTree\nsize 1\nres 0.05\ndata\n\0\0`@\1\2\3\0", 66);
  const auto file = scratch("root_leaf.ot");
  std::ofstream(file, std::ios::binary) << bytes;
  std::unique_ptr<octomap::AbstractOcTree> theirs_tree(octomap::AbstractOcTree::read(file.string()));
  auto* tree = dynamic_cast<octomap::ColorOcTree*>(theirs_tree.get());
  REQUIRE(tree != nullptr);
  CHECK(tree->size() == 1);
  CHECK(tree->getNumLeafNodes() == 1);
  const sem::OctoMap map = sem::formats::parse_octomap(file.string(), bytes);
  CHECK(map.nodes == 1);
  CHECK(map.inner_nodes == 0);
  REQUIRE(map.leaves.size() == 1);
  CHECK(map.leaves[0].depth == 0);
  CHECK(map.leaves[0].size_m == Approx(0.05 * 65536));
  CHECK(map.occupied_cells == uint64_t{1} << 48);
}

TEST_CASE("OctoMap reader places child i along x, y, z by its bits and refuses bad files with the line or byte", "[semantic]") {
  namespace fmt = sem::formats;
  SECTION("a root with a free and an occupied child") {
    // 0x09 = 0b00'00'10'01: child 0 free (01), child 1 occupied (10).
    const sem::OctoMap m = fmt::parse_octomap("t.bt", kBtHeader + std::string("\x09\x00", 2));
    REQUIRE(m.leaves.size() == 2);
    CHECK(m.nodes == 3);
    CHECK_FALSE(m.leaves[0].occupied);
    CHECK(m.leaves[1].occupied);
    CHECK(m.leaves[0].depth == 1);
    CHECK(m.leaves[0].size_m == Approx(3276.8).margin(1e-9));
    CHECK(m.leaves[0].centre_m.isApprox(Eigen::Vector3d(-1638.4, -1638.4, -1638.4)));
    CHECK(m.leaves[1].centre_m.isApprox(Eigen::Vector3d(1638.4, -1638.4, -1638.4)));
    CHECK(m.occupied_cells == uint64_t{1} << 45);
    // 2^45 points are no cloud.
    CHECK_THAT(error_of("t.bt", kBtHeader + std::string("\x09\x00", 2)), Catch::Contains("t.bt: 35184372088832 occupied cells"));
  }
  SECTION("a leaf at depth 16 is one cell, its centre half a cell off the key") {
    // Fifteen inner nodes down child 7 (+x +y +z), then child 0 occupied at depth 16.
    std::string tree;
    for (int d = 0; d < 15; ++d) tree += std::string("\x00\xc0", 2);
    tree += std::string("\x02\x00", 2);
    const auto m = fmt::parse_octomap("t.bt", "# Octomap OcTree binary file\nid OcTree\nsize 17\nres 0.05\ndata\n" + tree);
    REQUIRE(m.leaves.size() == 1);
    CHECK(m.leaves[0].depth == 16);
    CHECK(m.leaves[0].size_m == Approx(0.05).margin(1e-12));
    // Keys 32768 + 16384 + ... + 2 = 65534 on each axis → centre (65534 − 32768 + 0.5) · res.
    CHECK(m.leaves[0].centre_m.isApprox(Eigen::Vector3d::Constant(32766.5 * 0.05)));
    CHECK(sem::occupied_voxels(m).size() == 1);
  }
  SECTION("errors") {
    CHECK_THAT(error_of("t.bt", "# Octomap OcTree binary file\nid OcTree\nsize 3\nres 0.1\ndata\n\x09"),
               Catch::Contains("t.bt: byte 59: tree data truncated: a node needs 2 bytes, 1 left"));
    CHECK_THAT(error_of("t.bt", "# Octomap OcTree binary file\nid OcTree\nsize 3\nres x\ndata\n"),
               Catch::Contains("t.bt:4: res: not a number: 'x'"));
    CHECK_THAT(error_of("t.bt", "# Octomap OcTree binary file\nid OcTree\nsize 3\nres -1\ndata\n"),
               Catch::Contains("t.bt:4: res: must be a positive number"));
    CHECK_THAT(error_of("t.bt", "# Octomap OcTree binary file\nid CountingOcTree\nsize 3\nres 0.1\ndata\n"),
               Catch::Contains("t.bt:2: id: 'CountingOcTree' is not an occupancy tree"));
    CHECK_THAT(error_of("t.bt", "# Octomap OcTree binary file\nid OcTree\nsize 4\nres 0.1\ndata\n" + std::string("\x09\x00", 2)),
               Catch::Contains("t.bt:3: size: 4 nodes announced, the tree has 3"));
    CHECK_THAT(error_of("t.bt", kBtHeader + std::string("\x09\x00\x00", 3)), Catch::Contains("t.bt: byte 61: 1 bytes after the end of the tree"));
    CHECK_THAT(error_of("t.bt", kBtHeader + std::string("\x00\x00", 2)), Catch::Contains("t.bt: byte 59: an inner node without children"));
    CHECK_THAT(error_of("t.bt", "# Octomap OcTree binary file\nid OcTree\nsize 3\nres 0.1\n"), Catch::Contains("t.bt:4: data: missing"));
    CHECK_THAT(error_of("t.bt", "# Octomap OcTree binary file\nid OcTree\nres 0.1\ndata\n"), Catch::Contains("t.bt:4: size: missing"));
    CHECK_THAT(error_of("t.bt", "# Octomap OcTree binary file\nid OcTree\nid OcTree\n"), Catch::Contains("t.bt:3: id: given twice"));
    CHECK_THAT(error_of("t.bt", "# Octomap OcTree binary file\nid OcTree\ncolour 3\n"), Catch::Contains("t.bt:3: unknown header key 'colour'"));
    CHECK_THAT(error_of("t.ot", "ply\n"), Catch::Contains("t.ot:1: not an OctoMap file"));
    // Seventeen levels of inner nodes.
    std::string deep;
    for (int d = 0; d < 16; ++d) deep += std::string("\x03\x00", 2);
    CHECK_THAT(error_of("t.bt", "# Octomap OcTree binary file\nid OcTree\nsize 17\nres 0.1\ndata\n" + deep),
               Catch::Contains("t.bt: byte 90: a node at depth 16 has children: the tree is deeper than 16 levels"));
    // .ot: a float and a child byte per node.
    const std::string ot = "# Octomap OcTree file\nid OcTree\nsize 2\nres 0.1\ndata\n";
    const std::string node = std::string("\x00\x00\x60\x40", 4);  // 3.5
    CHECK(fmt::parse_octomap("t.ot", ot + node + "\x01" + node + std::string("\x00", 1)).leaves.size() == 1);
    CHECK_THAT(error_of("t.ot", ot + node + "\x01" + node), Catch::Contains("t.ot: byte 57: tree data truncated: a node needs 5 bytes, 4 left"));
    std::string ot_deep;
    for (int d = 0; d < 17; ++d) ot_deep += node + "\x01";
    CHECK_THAT(error_of("t.ot", "# Octomap OcTree file\nid OcTree\nsize 17\nres 0.1\ndata\n" + ot_deep),
               Catch::Contains("deeper than 16 levels"));
  }
}

namespace {

// Points with values that float and double keep apart, and unit normals.
vtkNew<vtkPoints> test_points(int type, int n) {
  vtkNew<vtkPoints> points;
  points->SetDataType(type);
  for (int i = 0; i < n; ++i) points->InsertNextPoint(0.1 * i - 3.3, -1.0 / (i + 1), 1e3 + 0.01 * i);
  return points;
}

vtkNew<vtkFloatArray> test_normals(int n) {
  vtkNew<vtkFloatArray> normals;
  normals->SetNumberOfComponents(3);
  normals->SetName("Normals");
  for (int i = 0; i < n; ++i) normals->InsertNextTuple3(std::cos(i), std::sin(i), 0.0);
  return normals;
}

// Binary data is exact; VTK's ASCII writer prints floats with 6 significant
// digits (doubles with enough for a float).
void check_points(const sem::Cloud& cloud, vtkPoints* points, bool exact) {
  REQUIRE(cloud.size() == static_cast<size_t>(points->GetNumberOfPoints()));
  for (vtkIdType i = 0; i < points->GetNumberOfPoints(); ++i) {
    double p[3];
    points->GetPoint(i, p);
    const Eigen::Vector3f expected = Eigen::Vector3d(p[0], p[1], p[2]).cast<float>();
    const Eigen::Vector3f& got = cloud.points[static_cast<size_t>(i)];
    if (exact) REQUIRE(got == expected);
    else REQUIRE((got - expected).cwiseAbs().maxCoeff() <= 1e-5f * expected.cwiseAbs().maxCoeff());
  }
}

}  // namespace

TEST_CASE("VTK reader reads the points and normals VTK's own legacy writers write", "[semantic]") {
  const int n = 50;
  const auto [binary, version, type] = GENERATE(table<bool, int, int>({{false, 51, VTK_FLOAT},
                                                                        {true, 51, VTK_FLOAT},
                                                                        {false, 42, VTK_DOUBLE},
                                                                        {true, 42, VTK_DOUBLE},
                                                                        {true, 51, VTK_DOUBLE}}));
  CAPTURE(binary, version, type);
  const auto file = scratch("poly.vtk").string();
  auto points = test_points(type, n);

  SECTION("POLYDATA with vertices, a polygon, scalars, normals and field data") {
    vtkNew<vtkPolyData> poly;
    poly->SetPoints(points);
    vtkNew<vtkCellArray> verts, polys;
    for (vtkIdType i = 0; i < n; ++i) verts->InsertNextCell(1, &i);
    const vtkIdType tri[3] = {0, 1, 2};
    polys->InsertNextCell(3, tri);
    poly->SetVerts(verts);
    poly->SetPolys(polys);
    poly->GetPointData()->SetNormals(test_normals(n));
    vtkNew<vtkIntArray> label;
    label->SetName("label");
    for (int i = 0; i < n; ++i) label->InsertNextValue(-i);
    poly->GetPointData()->SetScalars(label);
    vtkNew<vtkDoubleArray> extra;
    extra->SetName("extra");
    extra->SetNumberOfComponents(2);
    for (int i = 0; i < n; ++i) extra->InsertNextTuple2(i, 2.0 * i);
    poly->GetPointData()->AddArray(extra);
    vtkNew<vtkPolyDataWriter> writer;
    writer->SetInputData(poly);
    writer->SetFileName(file.c_str());
    writer->SetFileVersion(version);
    binary ? writer->SetFileTypeToBinary() : writer->SetFileTypeToASCII();
    REQUIRE(writer->Write() == 1);

    const sem::Cloud cloud = sem::read_cloud(file);
    check_points(cloud, points, binary || type == VTK_DOUBLE);
    REQUIRE(cloud.normals.size() == cloud.size());
    for (int i = 0; i < n; ++i)
      CHECK((cloud.normals[static_cast<size_t>(i)] - Eigen::Vector3d(std::cos(i), std::sin(i), 0).cast<float>()).norm() < 1e-6f);
  }
  SECTION("UNSTRUCTURED_GRID") {
    vtkNew<vtkUnstructuredGrid> grid;
    grid->SetPoints(points);
    const vtkIdType tet[4] = {0, 1, 2, 3};
    grid->InsertNextCell(VTK_TETRA, 4, tet);
    vtkNew<vtkUnstructuredGridWriter> writer;
    writer->SetInputData(grid);
    writer->SetFileName(file.c_str());
    writer->SetFileVersion(version);
    binary ? writer->SetFileTypeToBinary() : writer->SetFileTypeToASCII();
    REQUIRE(writer->Write() == 1);
    const sem::Cloud cloud = sem::read_cloud(file);
    check_points(cloud, points, binary || type == VTK_DOUBLE);
    CHECK(cloud.normals.empty());
  }
  SECTION("STRUCTURED_GRID") {
    vtkNew<vtkStructuredGrid> grid;
    grid->SetDimensions(5, 10, 1);
    grid->SetPoints(points);
    vtkNew<vtkStructuredGridWriter> writer;
    writer->SetInputData(grid);
    writer->SetFileName(file.c_str());
    writer->SetFileVersion(version);
    binary ? writer->SetFileTypeToBinary() : writer->SetFileTypeToASCII();
    REQUIRE(writer->Write() == 1);
    check_points(sem::read_cloud(file), points, binary || type == VTK_DOUBLE);
  }
}

TEST_CASE("VTK reader reads PCL's saveVTKFile and refuses bad files with the line or byte", "[semantic]") {
  SECTION("PCL's writer (ASCII POLYDATA, 5 significant digits)") {
    pcl::PointCloud<pcl::PointXYZ> pcl_cloud;
    for (float i = 0; i < 20; ++i) pcl_cloud.push_back(pcl::PointXYZ(0.5f * i, -0.25f * i, 1.0f + 0.125f * i));
    pcl::PCLPointCloud2 blob;
    pcl::toPCLPointCloud2(pcl_cloud, blob);
    const auto file = scratch("pcl.vtk").string();
    REQUIRE(pcl::io::saveVTKFile(file, blob) == 0);
    const sem::Cloud cloud = sem::read_cloud(file);
    REQUIRE(cloud.size() == pcl_cloud.size());
    for (size_t i = 0; i < cloud.size(); ++i) CHECK((cloud.points[i] - pcl_cloud[i].getVector3fMap()).norm() < 1e-4f);
  }
  SECTION("errors") {
    const std::string head = "# vtk DataFile Version 3.0\ntitle\n";
    CHECK_THAT(error_of("t.vtk", "# vtk DataFile\n"), Catch::Contains("t.vtk:1: not a legacy VTK file"));
    CHECK_THAT(error_of("t.vtk", head + "TEXT\n"), Catch::Contains("t.vtk:3: expected ASCII or BINARY"));
    CHECK_THAT(error_of("t.vtk", head + "ASCII\n"), Catch::Contains("t.vtk:3: expected 'DATASET <type>'"));
    CHECK_THAT(error_of("t.vtk", head + "ASCII\nDATASET STRUCTURED_POINTS\n"),
               Catch::Contains("t.vtk:4: DATASET: 'STRUCTURED_POINTS' has no point list"));
    CHECK_THAT(error_of("t.vtk", head + "ASCII\nDATASET POLYDATA\nPOINTS 2 float\n1 2 3\n4 5\n"),
               Catch::Contains("t.vtk:5: POINTS: file ends after 5 of 6 values"));
    CHECK_THAT(error_of("t.vtk", head + "ASCII\nDATASET POLYDATA\nPOINTS 2 float\n1 2 3\n4 5 x\n"),
               Catch::Contains("t.vtk:7: POINTS: not a number: 'x'"));
    CHECK_THAT(error_of("t.vtk", head + "ASCII\nDATASET POLYDATA\nPOINTS 1 quaternion\n"),
               Catch::Contains("t.vtk:5: POINTS: unsupported value type 'quaternion'"));
    CHECK_THAT(error_of("t.vtk", head + "ASCII\nDATASET POLYDATA\nPOINTS 1 float\n1 2 3\nSPHERES 1\n"),
               Catch::Contains("t.vtk:7: unknown keyword 'SPHERES'"));
    CHECK_THAT(error_of("t.vtk", head + "ASCII\nDATASET POLYDATA\nPOINTS 9999999 float\n1 2 3\n"),
               Catch::Contains("t.vtk:5: POINTS: 9999999 x 3 values cannot fit"));
    CHECK_THAT(error_of("t.vtk", head + "ASCII\nDATASET POLYDATA\nPOINTS 2 float\n1 2 3 4 5 6\nPOINT_DATA 1\nNORMALS n float\n0 0 1\n"),
               Catch::Contains("t.vtk:8: NORMALS: 1 normals for 2 points"));
    CHECK_THAT(error_of("t.vtk", head + "ASCII\nDATASET POLYDATA\n"), Catch::Contains("t.vtk:4: POINTS: missing"));
    CHECK_THAT(error_of("t.vtk", head + "BINARY\nDATASET POLYDATA\nPOINTS 2 float\n" + std::string(20, '\0')),
               Catch::Contains("t.vtk: byte 72: POINTS: binary data truncated: 6 values need 24 bytes, 20 left"));
    // A point of NaNs is dropped with its normal; the rest are read.
    const auto c = sem::parse_cloud("t.vtk", head + "ASCII\nDATASET POLYDATA\nPOINTS 2 double\nnan 0 0 1 2 3\n"
                                                   "CELL_DATA 0\nPOINT_DATA 2\nNORMALS n float\n1 0 0 0 0 2\n");
    REQUIRE(c.size() == 1);
    CHECK(c.points[0] == Eigen::Vector3f(1, 2, 3));
    CHECK(c.normals[0] == Eigen::Vector3f(0, 0, 1));
  }
}

TEST_CASE("rise-semantic segment reads freiburg1_360.bt and finds its floor and ceiling", "[semantic]") {
  const std::string path = data_file("pointclouds/ANYbotics_grid_map/freiburg1_360.bt");
  if (path.empty()) {
    WARN("skipped: RISE_TEST_DATA/pointclouds/ANYbotics_grid_map/freiburg1_360.bt not found");
    return;
  }
  const auto out = scratch("segment.txt");
  const std::string cmd = std::string(RISE_BINARY_DIR) + "/bin/rise-semantic segment " + path + " > " + out.string() + " 2>&1";
  REQUIRE(std::system(cmd.c_str()) == 0);
  std::ifstream in(out);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  INFO(text);
  CHECK_THAT(text, Catch::Contains(": 1019366 points"));
  // The occupied cells' heights peak at -0.1..0.1 m and 2.8..3.0 m.
  const auto at = text.find("floor ");
  REQUIRE(at != std::string::npos);
  double floor_m = NAN, ceiling_m = NAN;
  REQUIRE(std::sscanf(text.c_str() + at, "floor %lf m, ceiling %lf m", &floor_m, &ceiling_m) == 2);
  CHECK(floor_m == Approx(0.0).margin(0.05));
  CHECK(ceiling_m == Approx(2.95).margin(0.1));
}
