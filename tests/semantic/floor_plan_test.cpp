// segment_floor_plan: walls and doorways from occupancy grids, on small
// drawn grids and on the real buildings of shared/data against their truth
// files (tests/data/buildings).

#include <catch2/catch.hpp>

#include <cstdio>
#include <filesystem>
#include <map>
#include <string>

#include "semantic/cloud_io.hpp"
#include "semantic/floor_plan.hpp"
#include "semantic/occupancy_grid.hpp"
#include "tests/semantic/building_truth.hpp"
#include "tests/test_data.hpp"

namespace fs = std::filesystem;
using namespace rise::semantic;
using namespace rise::semantic::testing;

namespace {

// A grid of `w` x `h` unknown cells of 5 cm, origin at 0, 0.
OccupancyGrid blank(int w, int h) {
  OccupancyGrid g;
  g.resolution_m = 0.05;
  g.width = w, g.height = h;
  g.cells.assign(static_cast<std::size_t>(w) * h, CellState::Unknown);
  return g;
}

void fill(OccupancyGrid& g, double x0, double y0, double x1, double y1, CellState s) {
  for (int r = 0; r < g.height; ++r)
    for (int c = 0; c < g.width; ++c) {
      const Eigen::Vector2d p = g.center(c, r);
      if (p.x() >= x0 && p.x() < x1 && p.y() >= y0 && p.y() < y1) g.at(c, r) = s;
    }
}

// Two 4 x 3 m rooms side by side (x 0..4 and 4.3..8.3, y 0..3), their
// shared wall 0.3 m thick seen as two faces with unknown cells between
// and, when `door`, a 0.9 m doorway in it at y 1.0..1.9; outer walls one
// cell thick, seen from inside only.
OccupancyGrid two_rooms(bool door) {
  OccupancyGrid g = blank(180, 80);
  fill(g, 0.2, 0.2, 8.6, 3.6, CellState::Free);
  fill(g, 4.2, 0.2, 4.5, 3.6, CellState::Unknown);    // inside the shared wall
  fill(g, 0.15, 0.15, 8.65, 0.2, CellState::Occupied);  // south
  fill(g, 0.15, 3.6, 8.65, 3.65, CellState::Occupied);  // north
  fill(g, 0.15, 0.15, 0.2, 3.65, CellState::Occupied);  // west
  fill(g, 8.6, 0.15, 8.65, 3.65, CellState::Occupied);  // east
  fill(g, 4.15, 0.2, 4.2, 3.6, CellState::Occupied);    // shared wall, west face
  fill(g, 4.5, 0.2, 4.55, 3.6, CellState::Occupied);    // ... east face
  if (door) {
    fill(g, 4.15, 1.0, 4.55, 1.9, CellState::Free);
  }
  return g;
}

// The walls within 0.1 m of x = `x` running along y.
std::vector<Wall> walls_at_x(const Segmentation& seg, double x) {
  std::vector<Wall> out;
  for (const Wall& w : seg.walls)
    if (std::abs(w.direction().x()) < 0.1 && std::abs((w.from_m.x() + w.to_m.x()) / 2 - x) < 0.1) out.push_back(w);
  return out;
}

}  // namespace

TEST_CASE("a wall seen as two faces is one wall with its thickness, and its doorway an opening with a lintel",
          "[semantic]") {
  FloorPlanSettings st;
  st.wall_height_m = 2.6;
  st.door_height_m = 2.1;
  const Segmentation seg = segment_floor_plan(two_rooms(true), st);
  const auto shared = walls_at_x(seg, 4.35);
  REQUIRE(shared.size() == 1);
  CHECK(shared[0].thickness_m == Approx(0.4).margin(0.06));
  CHECK(shared[0].height_m == 2.6);
  CHECK(shared[0].both_faces_seen);
  REQUIRE(shared[0].openings.size() == 1);
  CHECK(shared[0].openings[0].width_m == Approx(0.9).margin(0.1));
  CHECK(shared[0].openings[0].height_m == 2.1);
  REQUIRE(seg.doors.size() == 1);
  const Door& d = seg.doors[0];
  CHECK(d.center_m.x() == Approx(4.35).margin(0.05));
  CHECK(d.center_m.y() == Approx(1.45).margin(0.05));
  CHECK(d.lintel);
  REQUIRE(d.wall >= 0);
  CHECK(seg.walls[static_cast<std::size_t>(d.wall)].openings.size() == 1);
  // The outer walls, seen from one side only, are walls too: 4 + the shared one.
  CHECK(seg.walls.size() == 5);
  CHECK_FALSE(seg.ceiling.found);
  CHECK(seg.obstacles.empty());
  CHECK(seg.floor.min_m.x() == Approx(0.2).margin(0.06));
  CHECK(seg.floor.max_m.x() == Approx(8.6).margin(0.06));
}

TEST_CASE("a doorway a wall meets at its jamb is as wide as the gap the wall's box leaves", "[semantic]") {
  // The two rooms' 0.9 m doorway (y 1.0..1.9), and in the east room a
  // 0.3 m wall along x from the shared wall's east face, y 0.9..1.2: its
  // box, lengthened by half its thickness past its line's end at the
  // shared wall's centre line, reaches a little further into the gap than
  // its cells do.
  OccupancyGrid g = two_rooms(true);
  fill(g, 4.55, 0.9, 7.0, 1.2, CellState::Occupied);
  const Segmentation seg = segment_floor_plan(g, {});
  const auto shared = walls_at_x(seg, 4.35);
  REQUIRE(shared.size() == 1);
  REQUIRE(shared[0].openings.size() == 1);
  const double at = shared[0].from_m.y() < shared[0].to_m.y() ? shared[0].from_m.y() + shared[0].openings[0].at_m
                                                              : shared[0].from_m.y() - shared[0].openings[0].at_m -
                                                                    shared[0].openings[0].width_m;
  INFO("opening from y " << at << ", " << shared[0].openings[0].width_m << " m wide");
  CHECK(shared[0].openings[0].width_m == Approx(0.7).margin(0.03));  // 0.75 between the cells
  CHECK(at == Approx(1.2).margin(0.06));
  REQUIRE(seg.doors.size() == 1);
  CHECK(seg.doors[0].width_m == shared[0].openings[0].width_m);
  // The wall across: its box ends where the opening begins.
  const Wall* across = nullptr;
  for (const Wall& w : seg.walls)
    if (std::abs(w.direction().y()) < 0.1 && std::abs(w.from_m.y() - 1.05) < 0.1) across = &w;
  REQUIRE(across != nullptr);
  CHECK(across->from_m.y() + across->thickness_m / 2 <= at + 0.01);  // (1.225 and 1.19 before the clearing)
}

TEST_CASE("a gap of door width whose far side is unknown is no doorway, and a wall without one is whole",
          "[semantic]") {
  SECTION("no gap: one wall, no door") {
    const Segmentation seg = segment_floor_plan(two_rooms(false));
    CHECK(walls_at_x(seg, 4.35).size() == 1);
    CHECK(seg.doors.empty());
  }
  SECTION("the far side unknown") {
    OccupancyGrid g = two_rooms(true);
    fill(g, 4.55, 0.2, 8.6, 3.6, CellState::Unknown);
    fill(g, 4.5, 0.2, 4.55, 3.6, CellState::Unknown);
    fill(g, 4.15, 1.0, 4.55, 1.9, CellState::Unknown);
    const Segmentation seg = segment_floor_plan(g);
    CHECK(seg.doors.empty());
  }
}

TEST_CASE("thin diagonal clutter and specks in a room are not walls", "[semantic]") {
  OccupancyGrid g = two_rooms(false);
  for (int k = 0; k < 30; ++k) {  // a 1.5 m line at 30 deg to the walls, one cell wide
    const Eigen::Vector2i c = g.cell_of({1.0 + 0.05 * k * std::cos(0.52), 1.0 + 0.05 * k * std::sin(0.52)});
    g.at(c.x(), c.y()) = CellState::Occupied;
  }
  fill(g, 2.5, 2.5, 2.6, 2.6, CellState::Occupied);
  const Segmentation seg = segment_floor_plan(g);
  CHECK(seg.walls.size() == 5);
}

// A room whose south wall runs at 17° to the others, drawn as a depth
// camera's map draws it: a staircase of 0.75 m dashes three cells thick,
// each 0.25 m lower than the last and a cell apart from it (PWR's south-east
// wall). The dashes are each too short for a wall, and the wall too little
// of the map's edges to be a direction of its own.
TEST_CASE("a slanted wall in no direction of its own is one wall, not its staircase of dashes", "[semantic]") {
  OccupancyGrid g = blank(160, 130);
  constexpr int kDashes = 9;
  for (int i = 0; i < kDashes; ++i) {
    const double x = 0.2 + 0.8 * i, y = 3.0 - 0.25 * i;
    fill(g, x, y + 0.15, x + 0.8, 6.2, CellState::Free);
    fill(g, x, y, x + 0.75, y + 0.15, CellState::Occupied);
  }
  fill(g, 0.15, 6.2, 7.45, 6.25, CellState::Occupied);  // north
  fill(g, 0.15, 3.0, 0.2, 6.25, CellState::Occupied);   // west
  fill(g, 7.4, 1.0, 7.45, 6.25, CellState::Occupied);   // east
  const Segmentation seg = segment_floor_plan(g);
  const Eigen::Vector2d slant = Eigen::Vector2d(0.8, -0.25).normalized();
  const Eigen::Vector2d first_dash{0.2 + 0.375, 3.0 + 0.075};  // the dashes' centres lie on this line along `slant`
  const Eigen::Vector2d across{-slant.y(), slant.x()};
  int slanted = 0;
  for (const Wall& w : seg.walls) {
    INFO("wall (" << w.from_m.transpose() << ") - (" << w.to_m.transpose() << "), " << w.thickness_m << " m thick");
    if (std::abs(w.direction().dot(slant)) < std::cos(3.0 * 3.14159265358979 / 180)) continue;
    ++slanted;
    CHECK((w.to_m - w.from_m).norm() >= 0.9 * (kDashes - 1) * Eigen::Vector2d(0.8, 0.25).norm());
    // On the dashes' centre line, not beside it on one edge of the staircase
    // (the dashes' own cells lie within 0.19 m of that line).
    CHECK(std::abs(((w.from_m + w.to_m) / 2 - first_dash).dot(across)) < 0.05);
    CHECK(w.thickness_m >= 0.15);
    CHECK(w.thickness_m <= 0.45);
  }
  CHECK(slanted == 1);
  CHECK(seg.walls.size() == 4);  // the slanted one, north, west, east: no dash a wall of its own
}

// A 5 x 3 m room (x 0.2..5.2, y 0.2..3.2), walls one cell thick, with a
// cabinet 1.5 m long and 0.25 m deep against the west end of its south
// wall: the cabinet's top face (y 0.4..0.45) and the wall's inner face
// are joined as one wall's two faces (unknown cells between them).
TEST_CASE("a wall whose second face is a short cabinet beside it keeps the wall's direction", "[semantic]") {
  OccupancyGrid g = blank(110, 70);
  fill(g, 0.2, 0.2, 5.2, 3.2, CellState::Free);
  fill(g, 0.2, 0.2, 1.7, 0.4, CellState::Unknown);      // inside the cabinet
  fill(g, 0.2, 0.4, 1.7, 0.45, CellState::Occupied);    // its top
  fill(g, 1.65, 0.2, 1.7, 0.45, CellState::Occupied);   // its east side
  fill(g, 0.15, 0.15, 5.25, 0.2, CellState::Occupied);  // south
  fill(g, 0.15, 3.2, 5.25, 3.25, CellState::Occupied);  // north
  fill(g, 0.15, 0.15, 0.2, 3.25, CellState::Occupied);  // west
  fill(g, 5.2, 0.15, 5.25, 3.25, CellState::Occupied);  // east
  const Segmentation seg = segment_floor_plan(g);
  int south = 0;
  for (const Wall& w : seg.walls) {
    INFO("wall (" << w.from_m.transpose() << ") - (" << w.to_m.transpose() << "), " << w.thickness_m << " m thick");
    if (std::abs(w.direction().x()) < 0.9 || (w.from_m.y() + w.to_m.y()) / 2 > 1.0) continue;
    ++south;
    // One line through both faces' cells tilts 2 degrees towards the cabinet.
    CHECK(std::abs(w.direction().y()) < std::sin(0.3 * 3.14159265358979 / 180));
    CHECK(w.length_m() >= 4.8);
  }
  CHECK(south == 1);
}

// A corridor (y 3.1..4.5) over a room (x 3..9, y 0.5..2.45), the wall
// between them (y 2.45..2.55) seen from x 5 on; west of it a doorway
// 4.1..5.0 whose far jamb is `jamb`: a stub 0.65 m long from the wall line
// into the corridor side, too short to be a wall, with unknown cells behind
// it (ACES's doorway at -7.6, -39.7); or a wall right across the line
// (a passage round a corner, no doorway).
OccupancyGrid corridor_over_room(bool stub) {
  OccupancyGrid g = blank(220, 100);
  fill(g, 3.0, 0.5, 9.0, 2.45, CellState::Free);         // the room
  fill(g, 0.5, 3.1, 10.5, 4.5, CellState::Free);         // the corridor
  fill(g, 4.1, 2.45, 10.5, 3.1, CellState::Free);        // ... beside the wall, east of the jamb
  fill(g, 2.95, 0.45, 9.05, 0.5, CellState::Occupied);   // the room's south wall
  fill(g, 2.95, 0.45, 3.0, 2.45, CellState::Occupied);   // ... west
  fill(g, 9.0, 0.45, 9.05, 2.55, CellState::Occupied);   // ... east
  fill(g, 5.0, 2.45, 9.05, 2.55, CellState::Occupied);   // the wall between room and corridor
  fill(g, 0.5, 4.5, 10.5, 4.55, CellState::Occupied);    // the corridor's north wall
  if (stub)
    fill(g, 3.95, 2.45, 4.1, 3.1, CellState::Occupied);
  else
    fill(g, 3.95, 0.5, 4.1, 4.5, CellState::Occupied);
  return g;
}

TEST_CASE("a doorway whose far jamb is a stub too short to be a wall is found on the grid itself", "[semantic]") {
  const Segmentation seg = segment_floor_plan(corridor_over_room(true));
  REQUIRE(seg.doors.size() == 1);
  CHECK(seg.doors[0].center_m.x() == Approx(4.55).margin(0.1));
  CHECK(seg.doors[0].center_m.y() == Approx(2.5).margin(0.1));
  CHECK(seg.doors[0].width_m == Approx(0.9).margin(0.1));
  // The wall goes on through the doorway to the stub.
  bool to_stub = false;
  for (const Wall& w : seg.walls)
    to_stub = to_stub || (std::abs(w.from_m.y() - 2.5) < 0.1 && std::min(w.from_m.x(), w.to_m.x()) < 4.2);
  CHECK(to_stub);
  // A wall right across the line beyond the gap: a passage round a corner.
  CHECK(segment_floor_plan(corridor_over_room(false)).doors.empty());
}

// Cells within `half` of the segment a..b set to `s`.
void fill_band(OccupancyGrid& g, const Eigen::Vector2d& a, const Eigen::Vector2d& b, double half, CellState s) {
  const Eigen::Vector2d d = (b - a).normalized();
  for (int r = 0; r < g.height; ++r)
    for (int c = 0; c < g.width; ++c) {
      const Eigen::Vector2d q = g.center(c, r) - a;
      const double along = q.dot(d);
      if (along >= 0 && along <= (b - a).norm() && std::abs(q.x() * d.y() - q.y() * d.x()) <= half) g.at(c, r) = s;
    }
}

// A wall along y = 2.5 between two free rooms (x 0.5..11.5, y 0.5..4.5)
// with a 1.0 m doorway at x 4.0..5.0 whose far jamb is a post 0.1 m wide,
// then a see-through side pane `pane_m` wide (free cells: the laser looked
// through it), then the wall again (Freiburg 101's hall at 4.0, 1.6); or,
// `across`, a wall 0.25 m thick right across the line there, the line
// ending at it (a passage round a corner beyond the post: ACES's map at
// 4 cm, 5.5, -40.9).
OccupancyGrid door_beside_pane(double pane_m, bool across = false) {
  OccupancyGrid g = blank(240, 100);
  fill(g, 0.5, 0.5, 11.5, 4.5, CellState::Free);
  fill(g, 0.45, 0.45, 11.55, 0.5, CellState::Occupied);  // outer walls
  fill(g, 0.45, 4.5, 11.55, 4.55, CellState::Occupied);
  fill(g, 0.45, 0.45, 0.5, 4.55, CellState::Occupied);
  fill(g, 11.5, 0.45, 11.55, 4.55, CellState::Occupied);
  fill(g, 0.5, 2.45, 4.0, 2.55, CellState::Occupied);  // the wall, the doorway's near jamb at 4.0
  fill(g, 5.0, 2.45, 5.1, 2.55, CellState::Occupied);  // the post
  if (across)
    fill(g, 5.1 + pane_m, 0.5, 5.35 + pane_m, 4.5, CellState::Occupied);
  else
    fill(g, 5.1 + pane_m, 2.45, 11.5, 2.55, CellState::Occupied);
  return g;
}

// A hall (x 1..23, y 1..11, free) whose north wall runs along x and whose
// south wall runs 10 degrees off it, from (3, 3) for 12 m, rooms behind it
// and a 0.9 m doorway in it 5 m along; a cabinet 1.5 x 0.4 m stands against
// the south wall on the hall's side 2 m along (Freiburg 101's hall: north
// wall at 168 deg, south wall at 178.5 deg).
OccupancyGrid hall_with_slanted_south_wall() {
  OccupancyGrid g = blank(480, 240);
  fill(g, 1.0, 0.5, 23.0, 11.0, CellState::Free);
  fill(g, 0.95, 11.0, 23.05, 11.05, CellState::Occupied);  // north
  fill(g, 0.95, 0.45, 1.0, 11.05, CellState::Occupied);    // west
  fill(g, 23.0, 0.45, 23.05, 11.05, CellState::Occupied);  // east
  fill(g, 0.95, 0.45, 23.05, 0.5, CellState::Occupied);    // the rooms' south wall
  const double a = 10.0 * 3.14159265358979 / 180.0;
  const Eigen::Vector2d o(3.0, 3.0), d(std::cos(a), std::sin(a)), n(-d.y(), d.x());
  fill_band(g, o, o + 12.0 * d, 0.06, CellState::Occupied);
  fill_band(g, o + 5.0 * d, o + 5.9 * d, 0.07, CellState::Free);                   // the doorway
  fill_band(g, o + 2.0 * d + 0.27 * n, o + 3.5 * d + 0.27 * n, 0.2, CellState::Occupied);  // the cabinet
  return g;
}

TEST_CASE("a doorway whose far jamb is a post beside a see-through side pane is a doorway, a post beside a gap a "
          "door wide is none",
          "[semantic]") {
  const Segmentation seg = segment_floor_plan(door_beside_pane(0.4));
  REQUIRE(seg.doors.size() == 1);
  CHECK(seg.doors[0].center_m.x() == Approx(4.5).margin(0.05));
  CHECK(seg.doors[0].center_m.y() == Approx(2.5).margin(0.05));
  CHECK(seg.doors[0].width_m == Approx(1.0).margin(0.06));
  // A post between two gaps a door wide is no jamb: the wall is open there;
  // nor is a post before a wall across the way.
  CHECK(segment_floor_plan(door_beside_pane(0.7)).doors.empty());
  CHECK(segment_floor_plan(door_beside_pane(0.4, true)).doors.empty());
}

TEST_CASE("a hall's south wall 10 degrees off its north wall keeps its own direction and its doorway", "[semantic]") {
  const Segmentation seg = segment_floor_plan(hall_with_slanted_south_wall());
  const double a = 10.0 * 3.14159265358979 / 180.0;
  const Eigen::Vector2d o(3.0, 3.0), d(std::cos(a), std::sin(a));
  double along_south = 0.0;
  for (const Wall& w : seg.walls) {
    const Eigen::Vector2d u = w.direction(), mid = (w.from_m + w.to_m) / 2 - o;
    if (std::abs(mid.x() * d.y() - mid.y() * d.x()) > 0.3 || mid.dot(d) < 0 || mid.dot(d) > 12) continue;
    INFO("a wall on the south wall's line: (" << w.from_m.transpose() << ") - (" << w.to_m.transpose() << ")");
    CHECK(std::abs(std::remainder(std::atan2(u.y(), u.x()) - a, 3.14159265358979)) < 1.0 * 3.14159265358979 / 180.0);
    along_south += (w.to_m - w.from_m).norm();
  }
  CHECK(along_south > 10.0);
  REQUIRE(seg.doors.size() == 1);
  // Along the wall where it is; across, the wall's line lies between the
  // wall and the cabinet joined to it (their two faces, nothing free between).
  const Eigen::Vector2d door = seg.doors[0].center_m - o;
  CHECK(door.dot(d) == Approx(5.45).margin(0.1));
  CHECK(std::abs(door.x() * d.y() - door.y() * d.x()) < 0.3);
  CHECK(seg.doors[0].width_m == Approx(0.9).margin(0.1));
}

TEST_CASE("segment_floor_plan refuses a grid with nothing to find", "[semantic]") {
  CHECK_THROWS_AS(segment_floor_plan(blank(10, 10)), std::invalid_argument);
  CHECK_THROWS_AS(segment_floor_plan(OccupancyGrid{}), std::invalid_argument);
}

// The goal (issue 15) is precision and recall >= 0.9 for walls and doorways
// on every building. Not reached yet: each building is held at what it
// measured (a little below, for the noise of a change elsewhere), so that
// no change makes a building worse unnoticed; raise a floor when a change
// lifts its building.
struct Floors {
  double wall_precision, wall_recall, door_precision, door_recall;
};
const std::map<std::string, Floors> kMeasured = {
    // stem            walls P  walls R  doors P  doors R   (measured 2026-12-02; csail: 2026-12-04; intel: 2026-12-05, fourth pass; pwr: 2026-12-05, slanted walls; aces: 2026-12-05, stub jambs)
    {"aces", {0.92, 0.95, 1.0, 1.0}},          // 0.936 0.956 1.00 1.00 (8 of 8)
    {"csail", {0.92, 0.97, 1.0, 1.0}},         // 0.925 0.980 1.00 (none found, none true) 1.00
    {"freiburg-101", {0.97, 0.9, 1.0, 1.0}},   // 0.984 0.920 1.00 1.00 (2 of 2; 2026-12-06: south wall's own direction, post jamb)
    {"intel", {0.89, 0.9, 1.0, 0.9}},          // 0.903 0.908 1.00 0.929 (13 of 14)
    {"pwr", {0.9, 0.9, 1.0, 1.0}},             // 0.914 0.926 1.00 (none found, none true) 1.00
    // pwr's walls hold 0.9 with the wedge's south wall in its truth (added 2026-12-05; 0.894 / 0.925 without it).
};

TEST_CASE("walls and doorways of the real buildings match their truth files no worse than measured",
          "[semantic]") {
  const fs::path dir = fs::path(RISE_SOURCE_DIR) / "tests" / "data" / "buildings";
  std::vector<fs::path> files;
  if (fs::is_directory(dir))
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().extension() == ".json") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  if (files.empty()) {
    WARN("skipped: no truth files in " << dir);
    return;
  }
  for (const fs::path& file : files) {
    const BuildingTruth truth = read_building_truth(file.string());
    const std::string map = rise::test::data_file(truth.source);
    if (map.empty()) {
      WARN("skipped " << file.filename() << ": " << truth.source << " not in RISE_TEST_DATA");
      continue;
    }
    const auto ends_with = [&](const std::string& tail) {
      return truth.source.size() >= tail.size() &&
             truth.source.compare(truth.source.size() - tail.size(), tail.size(), tail) == 0;
    };
    const bool ros = ends_with(".yaml");
    if (!ros && !ends_with(".log") && !ends_with(".log.gz")) {
      WARN("skipped " << file.filename() << ": " << truth.source << " is no 2D map (a 3D map's truth)");
      continue;
    }
    const OccupancyGrid grid = ros ? read_ros_map(map, truth.image.empty() ? "" : rise::test::data_file(truth.image))
                                   : grid_from_scans(read_carmen_log(map), truth.resolution_m);
    const Segmentation seg = segment_floor_plan(grid);
    const BuildingScore s = score_building(seg, truth);
    std::printf("%-16s walls: precision %.3f recall %.3f (%.1f m found, %.1f m true, %zu walls); doors: precision "
                "%.3f recall %.3f (%d found, %d true, %d matched)\n",
                file.stem().c_str(), s.wall_precision, s.wall_recall, s.detected_wall_m, s.truth_wall_m,
                seg.walls.size(), s.door_precision, s.door_recall, s.doors_detected, s.doors_truth, s.doors_matched);
    INFO(file.filename().string());
    const auto floors = kMeasured.find(file.stem().string());
    REQUIRE(floors != kMeasured.end());  // a new truth file gets its measured floors here
    CHECK(s.wall_precision >= floors->second.wall_precision);
    CHECK(s.wall_recall >= floors->second.wall_recall);
    CHECK(s.door_precision >= floors->second.door_precision);
    CHECK(s.door_recall >= floors->second.door_recall);
    for (const Obstacle& o : seg.obstacles) CHECK(o.size_m.maxCoeff() <= 3.0);
  }
}

TEST_CASE("the 3D map of a real room (OctoMap .bt) matches its truth file no worse than measured, walls from "
          "Hough lines and from its floor plan",
          "[semantic]") {
  const fs::path file = fs::path(RISE_SOURCE_DIR) / "tests" / "data" / "buildings" / "freiburg1_360.json";
  const BuildingTruth truth = read_building_truth(file.string());
  const std::string map = rise::test::data_file(truth.source);
  if (map.empty()) {
    WARN("skipped: " << truth.source << " not in RISE_TEST_DATA");
    return;
  }
  const Cloud cloud = read_cloud(map);
  for (const bool from_plan : {false, true}) {
    // walls P  walls R  doors P  doors R (measured 2026-12-02)
    const Floors floors = from_plan ? Floors{0.91, 0.79, 1.0, 0.0}    // 0.931 0.815 1.00 (none found) 0.00
                                    : Floors{0.95, 0.9, 1.0, 1.0};   // 0.979 0.915 1.00 1.00, 5 walls (41 before slabs merged)
    SegmentationSettings st;
    st.walls_from_floor_plan = from_plan;
    const Segmentation seg = segment(cloud, st);
    const BuildingScore s = score_building(seg, truth);
    std::printf("freiburg1_360 %-10s walls: precision %.3f recall %.3f (%.1f m found, %.1f m true, %zu walls); "
                "doors: precision %.3f recall %.3f (%d found, %d true, %d matched)\n",
                from_plan ? "plan" : "hough", s.wall_precision, s.wall_recall, s.detected_wall_m, s.truth_wall_m,
                seg.walls.size(), s.door_precision, s.door_recall, s.doors_detected, s.doors_truth, s.doors_matched);
    INFO((from_plan ? "walls from the floor plan" : "walls from Hough lines"));
    CHECK(s.wall_precision >= floors.wall_precision);
    CHECK(s.wall_recall >= floors.wall_recall);
    CHECK(s.door_precision >= floors.door_precision);
    CHECK(s.door_recall >= floors.door_recall);
    // A slab of voxels is one wall: the room's four walls, the south one in two beside its door.
    if (!from_plan) CHECK(seg.walls.size() <= 6);
  }
}
