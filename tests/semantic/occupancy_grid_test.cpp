// The 2D map readers on the real maps of shared/data (MANIFEST.md, section 5)
// and on small hand-written files, and the buildings' truth files
// (tests/data/buildings) against the grids they were drawn on.

#include <catch2/catch.hpp>
#include <json/json.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <fstream>
#include <map>
#include <optional>

#include "semantic/occupancy_grid.hpp"
#include "tests/test_data.hpp"

namespace fs = std::filesystem;
using namespace rise::semantic;

namespace {

const char* kPwrYaml = "pointclouds/mdrwiega_3d_map_server/pwr_d20_f5_m4/pwr_d20_f5_m4.yaml";
const char* kPwrPgm = "pointclouds/mdrwiega_3d_map_server/pwr_d20_f5_m4/pwr_d20_f5_m4.pgm";

size_t count(const OccupancyGrid& g, CellState s) { return static_cast<size_t>(std::count(g.cells.begin(), g.cells.end(), s)); }

// A scratch folder with the given files, removed at the end of the test.
struct Scratch {
  fs::path dir;
  explicit Scratch(const std::string& name) : dir(fs::temp_directory_path() / ("rise_grid_" + name)) {
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  ~Scratch() { fs::remove_all(dir); }
  std::string write(const std::string& file, const std::string& text) const {
    std::ofstream(dir / file, std::ios::binary) << text;
    return (dir / file).string();
  }
};

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST_CASE("the PWR map reads as map_server publishes it", "[semantic][grid]") {
  const std::string yaml = rise::test::data_file(kPwrYaml), pgm = rise::test::data_file(kPwrPgm);
  if (yaml.empty() || pgm.empty()) {
    WARN("skipped: " << kPwrYaml << " not in RISE_TEST_DATA");
    return;
  }
  SECTION("with its image named explicitly: 682 x 528 cells, 7739 occupied, 89523 free") {
    const OccupancyGrid g = read_ros_map(yaml, pgm);
    CHECK(g.width == 682);
    CHECK(g.height == 528);
    CHECK(g.resolution_m == Approx(0.05).margin(1e-12));
    CHECK(g.origin_m.x() == Approx(-15.837810).margin(1e-9));
    CHECK(g.origin_m.y() == Approx(-8.889314).margin(1e-9));
    CHECK(count(g, CellState::Occupied) == 7739);
    CHECK(count(g, CellState::Free) == 89523);
    CHECK(count(g, CellState::Unknown) == 682u * 528u - 7739 - 89523);
  }
  SECTION("its yaml names cartomap.pgm, which is not there: the error names it and the line") {
    const std::string e = error_of([&] { read_ros_map(yaml); });
    CHECK_THAT(e, Catch::Contains("pwr_d20_f5_m4.yaml:1: image: ") && Catch::Contains("cartomap.pgm: cannot open"));
  }
}

TEST_CASE("map_server's conversion: thresholds, negate, raw, and the image's top row is the highest y", "[semantic][grid]") {
  Scratch s("ros");
  // 3 x 2 pixels; top row: black (occupied), mid grey (unknown), white (free).
  s.write("m.pgm", "P2\n3 2\n255\n0 128 254\n254 254 0\n");
  const std::string base = "image: m.pgm\nresolution: 0.1\norigin: [1.0, -2.0, 0.0]\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
  SECTION("trinary") {
    const OccupancyGrid g = read_ros_map(s.write("t.yaml", base + "negate: 0\n"));
    REQUIRE(g.width == 3);
    REQUIRE(g.height == 2);
    CHECK(g.at(0, 1) == CellState::Occupied);
    CHECK(g.at(1, 1) == CellState::Unknown);
    CHECK(g.at(2, 1) == CellState::Free);
    CHECK(g.at(0, 0) == CellState::Free);
    CHECK(g.at(2, 0) == CellState::Occupied);
    CHECK(g.center(0, 0).x() == Approx(1.05));
    CHECK(g.center(0, 0).y() == Approx(-1.95));
  }
  SECTION("negate swaps black and white") {
    const OccupancyGrid g = read_ros_map(s.write("n.yaml", base + "negate: 1\n"));
    CHECK(g.at(0, 1) == CellState::Free);
    CHECK(g.at(2, 1) == CellState::Occupied);
  }
  SECTION("raw: the value is the occupancy in percent, above 100 unknown") {
    s.write("r.pgm", "P2\n3 1\n255\n0 100 255\n");
    const OccupancyGrid g = read_ros_map(s.write("r.yaml", base + "negate: 0\nmode: raw\n"), (s.dir / "r.pgm").string());
    CHECK(g.at(0, 0) == CellState::Free);
    CHECK(g.at(1, 0) == CellState::Occupied);
    CHECK(g.at(2, 0) == CellState::Unknown);
  }
  SECTION("16-bit PGM") {
    s.write("w.pgm", "P2\n2 1\n65535\n0 65535\n");
    const OccupancyGrid g = read_ros_map(s.write("w.yaml", base), (s.dir / "w.pgm").string());
    CHECK(g.at(0, 0) == CellState::Occupied);
    CHECK(g.at(1, 0) == CellState::Free);
  }
}

TEST_CASE("a bad map yaml is refused with its file, line and key", "[semantic][grid]") {
  Scratch s("bad");
  s.write("m.pgm", "P2\n1 1\n255\n0\n");
  SECTION("a resolution that is not a number") {
    const std::string y = s.write("a.yaml", "image: m.pgm\nresolution: fine\norigin: [0, 0, 0]\noccupied_thresh: 0.65\nfree_thresh: 0.2\n");
    CHECK_THAT(error_of([&] { read_ros_map(y); }), Catch::Contains("a.yaml:2: resolution: not a valid value: 'fine'"));
  }
  SECTION("a rotated origin") {
    const std::string y = s.write("b.yaml", "image: m.pgm\nresolution: 0.05\norigin: [0, 0, 0.5]\noccupied_thresh: 0.65\nfree_thresh: 0.2\n");
    CHECK_THAT(error_of([&] { read_ros_map(y); }), Catch::Contains("b.yaml:3: origin: yaw"));
  }
  SECTION("a missing threshold") {
    const std::string y = s.write("c.yaml", "image: m.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nfree_thresh: 0.2\n");
    CHECK_THAT(error_of([&] { read_ros_map(y); }), Catch::Contains("c.yaml:1: occupied_thresh: missing"));
  }
  SECTION("an unknown mode") {
    const std::string y = s.write("d.yaml", "image: m.pgm\nresolution: 0.05\norigin: [0, 0, 0]\noccupied_thresh: 0.65\nfree_thresh: 0.2\nmode: fancy\n");
    CHECK_THAT(error_of([&] { read_ros_map(y); }), Catch::Contains("d.yaml:6: mode: 'fancy'"));
  }
  SECTION("an image that is not one") {
    s.write("e.pgm", "not an image");
    const std::string y = s.write("e.yaml", "image: e.pgm\nresolution: 0.05\norigin: [0, 0, 0]\noccupied_thresh: 0.65\nfree_thresh: 0.2\n");
    CHECK_THAT(error_of([&] { read_ros_map(y); }), Catch::Contains("e.pgm: not an image"));
  }
}

TEST_CASE("the four CARMEN logs read with their scan and beam counts", "[semantic][grid]") {
  struct Log {
    const char* name;
    size_t scans, beams;
    double step_deg, max_range_m;
  };
  const Log logs[] = {{"intel", 910, 180, 1.0, 81.83},
                      {"freiburg-101", 292, 360, 0.5, 80.99},  // PARAM robot_front_laser_max
                      {"csail", 406, 361, 0.5, 50.0},          // PARAM robot_front_laser_max
                      {"aces", 440, 180, 1.0, 50.0}};
  for (const Log& l : logs) {
    const std::string rel = std::string("pointclouds/acschaefer_ple/") + l.name + "-corrected.log.gz";
    const std::string path = rise::test::data_file(rel);
    if (path.empty()) {
      WARN("skipped: " << rel << " not in RISE_TEST_DATA");
      continue;
    }
    INFO(l.name);
    const auto scans = read_carmen_log(path);
    REQUIRE(scans.size() == l.scans);
    for (const auto& s : scans) REQUIRE(s.ranges.size() == l.beams);
    CHECK(scans[0].start_angle_rad == Approx(-M_PI / 2));
    CHECK(scans[0].angle_step_rad * 180 / M_PI == Approx(l.step_deg));
    CHECK(scans[0].max_range_m == Approx(l.max_range_m).margin(1e-6));
  }
  const std::string intel = rise::test::data_file("pointclouds/acschaefer_ple/intel-corrected.log.gz");
  if (intel.empty()) return;
  SECTION("intel's first scan as the file has it") {
    const auto s = read_carmen_log(intel).front();
    CHECK(s.pose.x() == Approx(0.600266));
    CHECK(s.pose.y() == Approx(-0.0320327));
    CHECK(s.pose.z() == Approx(-0.354665));
    CHECK(s.time_s == Approx(32.9068));
  }
}

TEST_CASE("a bad CARMEN log is refused with its file and line", "[semantic][grid]") {
  Scratch s("carmen");
  SECTION("a FLASER line shorter than its count says") {
    const std::string p = s.write("a.log", "# comment\nODOM 0 0 0 0 0 0 1 h 1\nFLASER 3 1.0 2.0 3.0 0 0 0\n");
    CHECK_THAT(error_of([&] { read_carmen_log(p); }), Catch::Contains("a.log:3: FLASER: "));
  }
  SECTION("a range that is not a number") {
    const std::string p = s.write("b.log", "FLASER 2 1.0 x 0 0 0 0 0 0 5.0 h 5.0\n");
    CHECK_THAT(error_of([&] { read_carmen_log(p); }), Catch::Contains("b.log:1: range: not a number: 'x'"));
  }
  SECTION("a pose that is not a finite number") {
    const std::string p = s.write("e.log", "FLASER 2 1.0 2.0 nan 0 0 0 0 0 5.0 h 5.0\n");
    CHECK_THAT(error_of([&] { read_carmen_log(p); }), Catch::Contains("e.log:1: x: not a finite number: 'nan'"));
  }
  SECTION("a truncated gzip") {
    const std::string intel = rise::test::data_file("pointclouds/acschaefer_ple/intel-corrected.log.gz");
    if (intel.empty()) return;
    std::ifstream in(intel, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    const std::string p = s.write("c.log.gz", bytes.substr(0, 5000));
    CHECK_THAT(error_of([&] { read_carmen_log(p); }), Catch::Contains("c.log.gz: byte "));
  }
  SECTION("ROBOTLASER1 lines carry their own angles and range") {
    std::string flaser = "FLASER 180";
    for (int i = 0; i < 180; ++i) flaser += " 1.5";
    const std::string p = s.write("d.log",
        "ROBOTLASER1 0 -1.5 3.0 0.75 30 0.01 0 5 1 2 3 4 5 0 1.0 2.0 0.5 1.0 2.0 0.5 0 0 0 0 0 7.5 h 7.5\n" +
        flaser + " 0 0 0 0 0 0 8 h 8\n");
    const auto scans = read_carmen_log(p);
    REQUIRE(scans.size() == 2);
    CHECK(scans[0].ranges.size() == 5);
    CHECK(scans[0].start_angle_rad == Approx(-1.5));
    CHECK(scans[0].angle_step_rad == Approx(0.75));
    CHECK(scans[0].max_range_m == Approx(30));
    CHECK(scans[0].pose.y() == Approx(2.0));
    CHECK(scans[0].time_s == Approx(7.5));
    CHECK(scans[1].ranges.size() == 180);
  }
}

TEST_CASE("grid_from_scans makes intel's floor: 29 x 29 m of walls in a grid of about 43 x 41 m", "[semantic][grid]") {
  const std::string intel = rise::test::data_file("pointclouds/acschaefer_ple/intel-corrected.log.gz");
  if (intel.empty()) {
    WARN("skipped: intel-corrected.log.gz not in RISE_TEST_DATA");
    return;
  }
  const OccupancyGrid g = grid_from_scans(read_carmen_log(intel), 0.05);
  CHECK(g.resolution_m == 0.05);
  // The grid holds every beam: rays through the windows reach 7 m beyond the walls.
  CHECK(g.width * g.resolution_m == Approx(43.35).margin(1.0));
  CHECK(g.height * g.resolution_m == Approx(41.25).margin(1.0));
  CHECK(count(g, CellState::Free) > 10 * count(g, CellState::Occupied));
  // The building: the occupied cells bar the 0.5% farthest each way (stray
  // hits outside), x -10.4..18.7, y -23.1..5.8 as drawn in tests/data/buildings/intel.json.
  std::vector<double> xs, ys;
  for (int r = 0; r < g.height; ++r)
    for (int c = 0; c < g.width; ++c)
      if (g.at(c, r) == CellState::Occupied) xs.push_back(g.center(c, r).x()), ys.push_back(g.center(c, r).y());
  std::sort(xs.begin(), xs.end());
  std::sort(ys.begin(), ys.end());
  const size_t lo = xs.size() / 200, hi = xs.size() - 1 - xs.size() / 200;
  CHECK(xs[hi] - xs[lo] == Approx(29.1).margin(1.0));
  CHECK(ys[hi] - ys[lo] == Approx(28.9).margin(1.0));
}

namespace {

// The grid a truth file was drawn on: the map_server map it names, or the
// grid of the CARMEN log at its resolution.
std::optional<OccupancyGrid> truth_grid(const Json::Value& truth) {
  const std::string source = rise::test::data_file(truth["source"].asString());
  if (source.empty()) return std::nullopt;
  if (truth.isMember("image")) {
    const std::string image = rise::test::data_file(truth["image"].asString());
    if (image.empty()) return std::nullopt;
    return read_ros_map(source, image);
  }
  return grid_from_scans(read_carmen_log(source), truth["resolution_m"].asDouble());
}

bool occupied_near(const OccupancyGrid& g, const Eigen::Vector2d& p, double radius_m) {
  const int r = static_cast<int>(std::ceil(radius_m / g.resolution_m));
  const Eigen::Vector2i c = g.cell_of(p);
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx)
      if (g.contains(c.x() + dx, c.y() + dy) && g.at(c.x() + dx, c.y() + dy) == CellState::Occupied &&
          (g.center(c.x() + dx, c.y() + dy) - p).norm() <= radius_m + 0.5 * g.resolution_m)
        return true;
  return false;
}

}  // namespace

TEST_CASE("each building's truth file lies on its map: walls on occupied cells, doors in free space", "[semantic][grid]") {
  const fs::path dir = fs::path(RISE_SOURCE_DIR) / "tests/data/buildings";
  size_t files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".json") continue;
    ++files;
    INFO(entry.path().filename().string());
    std::ifstream in(entry.path());
    Json::Value truth;
    Json::CharReaderBuilder rb;
    std::string errors;
    REQUIRE(Json::parseFromStream(rb, in, &truth, &errors));
    REQUIRE(truth["note"].asString().size() > 100);
    REQUIRE(truth["walls"].size() > 0);
    if (truth["source"].asString().ends_with(".bt")) {
      WARN("not checked against its map: " << entry.path().filename().string() << " (an OctoMap; the 2D grid of a .bt is not built here)");
      continue;
    }
    const auto grid = truth_grid(truth);
    if (!grid) {
      WARN("skipped: " << truth["source"].asString() << " not in RISE_TEST_DATA");
      continue;
    }
    for (const auto& w : truth["walls"]) {
      REQUIRE(w.size() == 4);
      const Eigen::Vector2d a(w[0].asDouble(), w[1].asDouble()), b(w[2].asDouble(), w[3].asDouble());
      const int n = std::max(2, static_cast<int>((b - a).norm() / 0.05));
      int near = 0;
      for (int i = 0; i <= n; ++i) near += occupied_near(*grid, a + (b - a) * i / n, 0.15);
      INFO("wall " << w.toStyledString());
      CHECK(near >= 0.8 * (n + 1));
    }
    for (const auto& d : truth["doors"]) {
      INFO("door " << d.toStyledString());
      CHECK(d["width"].asDouble() >= 0.6);
      CHECK(d["width"].asDouble() <= 1.2);
      const Eigen::Vector2i c = grid->cell_of({d["center"][0].asDouble(), d["center"][1].asDouble()});
      REQUIRE(grid->contains(c.x(), c.y()));
      CHECK(grid->at(c.x(), c.y()) == CellState::Free);
    }
  }
  CHECK(files >= 1);
}
