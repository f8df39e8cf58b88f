#include "semantic/world_export.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace rise::semantic {
namespace {

constexpr double kDoorGapM = 0.01;  // the simulator hangs a door 1 cm above the floor

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4f", std::abs(v) < 5e-5 ? 0.0 : v);
  std::string s = buf;
  // Trim trailing zeros: 2.5000 → 2.5, 3.0000 → 3.0.
  while (s.size() > 2 && s.back() == '0' && s[s.size() - 2] != '.') s.pop_back();
  return s;
}

std::string deg(double rad) { return num(rad * 180.0 / M_PI); }

// A door exported as a hinged panel: its hinge, width and yaw. Between two
// walls the panel reaches half their thickness into each (as the world
// file's walls are lengthened by that much), in an opening it fills it.
struct Panel {
  Eigen::Vector2d hinge;
  double width_m, height_m, yaw_rad;
};

Panel panel_of(const Door& d) {
  const Eigen::Vector2d dir(std::cos(d.yaw_rad), std::sin(d.yaw_rad));
  const double width = d.wall < 0 ? d.width_m + d.wall_thickness_m : d.width_m;
  return {d.center_m - dir * width / 2, width, std::max(0.5, d.height_m - kDoorGapM), d.yaw_rad};
}

std::array<Eigen::Vector3d, 8> corners(const ModelBox& b) {
  std::array<Eigen::Vector3d, 8> out;
  const double c = std::cos(b.yaw_rad), s = std::sin(b.yaw_rad);
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d l((i & 1 ? 0.5 : -0.5) * b.size_m.x(), (i & 2 ? 0.5 : -0.5) * b.size_m.y(),
                            (i & 4 ? 0.5 : -0.5) * b.size_m.z());
    out[static_cast<std::size_t>(i)] = b.center_m + Eigen::Vector3d(c * l.x() - s * l.y(), s * l.x() + c * l.y(), l.z());
  }
  return out;
}

}  // namespace

std::vector<ModelBox> model_boxes(const SemanticNet& net, const ExportSettings& st) {
  const auto& seg = net.segmentation();
  const double z0 = seg.floor.height_m;
  std::vector<ModelBox> out;
  const auto& f = seg.floor;
  out.push_back({"floor", "floor", {(f.min_m.x() + f.max_m.x()) / 2, (f.min_m.y() + f.max_m.y()) / 2, z0 - 0.025},
                 {f.max_m.x() - f.min_m.x(), f.max_m.y() - f.min_m.y(), 0.05}, 0.0});
  for (const int id : net.of_kind(EntityKind::Wall)) {
    const Wall& w = seg.walls[static_cast<std::size_t>(net.entity(id).index)];
    const Eigen::Vector2d d = w.direction();
    const double yaw = std::atan2(d.y(), d.x());
    const auto piece = [&](double a0, double a1, double h0, double h1) {
      if (a1 - a0 < 1e-6 || h1 - h0 < 1e-6) return;
      const Eigen::Vector2d c = w.from_m + d * (a0 + a1) / 2;
      out.push_back({net.entity(id).name, "wall", {c.x(), c.y(), z0 + (h0 + h1) / 2}, {a1 - a0, w.thickness_m, h1 - h0}, yaw});
    };
    double start = -w.thickness_m / 2;
    for (const auto& o : w.openings) {
      piece(start, o.at_m, 0.0, w.height_m);
      piece(o.at_m, o.at_m + o.width_m, o.height_m, w.height_m);
      start = o.at_m + o.width_m;
    }
    piece(start, w.length_m() + w.thickness_m / 2, 0.0, w.height_m);
  }
  for (const int id : net.of_kind(EntityKind::Door)) {
    const Door& d = seg.doors[static_cast<std::size_t>(net.entity(id).index)];
    if (!d.panel) continue;
    const Panel p = panel_of(d);
    const Eigen::Vector2d c = p.hinge + Eigen::Vector2d(std::cos(p.yaw_rad), std::sin(p.yaw_rad)) * p.width_m / 2;
    out.push_back({net.entity(id).name, "door", {c.x(), c.y(), z0 + kDoorGapM + p.height_m / 2},
                   {p.width_m, st.door_thickness_m, p.height_m}, p.yaw_rad});
  }
  for (const int id : net.of_kind(EntityKind::Stairs)) {
    const Stairs& s = seg.stairs[static_cast<std::size_t>(net.entity(id).index)];
    const Eigen::Vector2d d(std::cos(s.yaw_rad), std::sin(s.yaw_rad));
    for (int i = 0; i <= s.steps; ++i) {
      const bool landing = i == s.steps;
      const double length = landing ? s.landing_m : s.tread_m;
      const double height = (landing ? s.steps : i + 1) * s.riser_m;
      const Eigen::Vector2d c = s.start_m + d * (i * s.tread_m + length / 2);
      out.push_back({net.entity(id).name, "stairs", {c.x(), c.y(), z0 + height / 2}, {length, s.width_m, height}, s.yaw_rad});
    }
  }
  if (seg.ceiling.found) {
    const auto& c = seg.ceiling;
    out.push_back({"ceiling", "ceiling",
                   {(c.min_m.x() + c.max_m.x()) / 2, (c.min_m.y() + c.max_m.y()) / 2, c.height_m + st.ceiling_thickness_m / 2},
                   {c.max_m.x() - c.min_m.x(), c.max_m.y() - c.min_m.y(), st.ceiling_thickness_m}, 0.0});
  }
  for (const int id : net.of_kind(EntityKind::Obstacle)) {
    const Obstacle& o = seg.obstacles[static_cast<std::size_t>(net.entity(id).index)];
    out.push_back({net.entity(id).name, "obstacle", o.center_m, o.size_m, o.yaw_rad});
  }
  return out;
}

namespace {

// The solids a robot's footprint runs into: model boxes reaching below its
// height (not a lintel over a doorway), other than floor and ceiling.
std::vector<ModelBox> footprint_solids(const SemanticNet& net, const ExportSettings& st) {
  const double top = net.segmentation().floor.height_m + st.robot_height_m;
  std::vector<ModelBox> out;
  for (auto& b : model_boxes(net, st))
    if (b.kind != "floor" && b.kind != "ceiling" && b.center_m.z() - b.size_m.z() / 2 < top) out.push_back(b);
  return out;
}

// Sets the cells of `mask` (one pixel per cell of `grid`) whose centres lie
// in a solid's footprint to 0.
void clear_solids(cv::Mat1b& mask, const OccupancyGrid& grid, const std::vector<ModelBox>& solids) {
  constexpr int kShift = 4;  // sub-cell corners
  for (const auto& b : solids) {
    const auto c = corners(b);
    std::vector<cv::Point> poly;
    for (const int i : {0, 1, 3, 2}) {
      const Eigen::Vector2d q = (c[static_cast<std::size_t>(i)].head<2>() - grid.origin_m) / grid.resolution_m -
                                Eigen::Vector2d(0.5, 0.5);
      poly.emplace_back(static_cast<int>(std::lround(q.x() * (1 << kShift))),
                        static_cast<int>(std::lround(q.y() * (1 << kShift))));
    }
    cv::fillConvexPoly(mask, poly, cv::Scalar(0), cv::LINE_8, kShift);
  }
}

// Metres from each cell of `mask` (255: passable) to the nearest cell that
// is not, less half a cell: the free radius around the cell's centre.
cv::Mat1f clearance_m(const cv::Mat1b& mask, double cell_m) {
  cv::Mat1f d;
  cv::distanceTransform(mask, d, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  d.convertTo(d, CV_32F, cell_m, -0.5 * cell_m);
  return d;
}

}  // namespace

OccupancyGrid floor_plan_of(const Cloud& cloud, const Segmentation& seg, const ExportSettings& st) {
  const double z0 = seg.floor.height_m;
  // A floor is as thick as its noise (Floor::noise_m): a Kinect's floor
  // voxels would otherwise make a room's floor occupied.
  const double band_m = std::max(0.03, seg.floor.noise_m), above_m = band_m + 0.02;
  Eigen::Vector2d lo = seg.floor.min_m, hi = seg.floor.max_m;
  for (const auto& p : cloud.points)
    if (p.allFinite() && p.z() > z0 - band_m && p.z() < z0 + st.robot_height_m) {
      lo = lo.cwiseMin(p.head<2>().cast<double>());
      hi = hi.cwiseMax(p.head<2>().cast<double>());
    }
  OccupancyGrid g;
  g.resolution_m = st.floor_plan_cell_m;
  g.origin_m = lo;
  const Eigen::Vector2d cells = (hi - lo) / g.resolution_m;
  if (!(cells.x() * cells.y() < 16e6))
    throw std::runtime_error("floor plan: " + num(hi.x() - lo.x()) + " x " + num(hi.y() - lo.y()) +
                             " m is more than 16 million cells of " + num(g.resolution_m) + " m");
  g.width = static_cast<int>(cells.x()) + 1;
  g.height = static_cast<int>(cells.y()) + 1;
  cv::Mat1b floor(g.height, g.width, uchar{0});
  cv::Mat1f above(g.height, g.width, 0.0f);
  for (const auto& p : cloud.points) {
    if (!p.allFinite()) continue;
    const Eigen::Vector2i c = g.cell_of(p.head<2>().cast<double>());
    if (!g.contains(c.x(), c.y())) continue;
    const double h = p.z() - z0;
    if (std::abs(h) < band_m) floor(c.y(), c.x()) = 255;
    else if (h > above_m && h < st.robot_height_m) above(c.y(), c.x()) += 1.0f;
  }
  // A far floor is seen on scan lines some cells apart.
  cv::morphologyEx(floor, floor, cv::MORPH_CLOSE, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(5, 5)));
  // Occupied: a point with another in the cells around it (a lone one is noise).
  cv::Mat1f around;
  cv::boxFilter(above, around, -1, cv::Size(3, 3), cv::Point(-1, -1), false);
  cv::Mat1b occupied;
  cv::bitwise_and(cv::Mat(above > 0.0f), cv::Mat(around >= 2.0f), occupied);
  g.cells.assign(static_cast<std::size_t>(g.width) * static_cast<std::size_t>(g.height), CellState::Unknown);
  for (int r = 0; r < g.height; ++r)
    for (int c = 0; c < g.width; ++c)
      g.at(c, r) = occupied(r, c) ? CellState::Occupied : floor(r, c) ? CellState::Free : CellState::Unknown;
  return g;
}

Eigen::Vector3d robot_start(const SemanticNet& net, const ExportSettings& st) {
  if (st.robot_start) return *st.robot_start;
  const auto& seg = net.segmentation();
  const double need = st.robot_half_width_m + st.robot_margin_m;
  OccupancyGrid fallback;
  if (!st.floor_plan) {
    // No floor plan: the floor's extent is free.
    fallback.resolution_m = st.floor_plan_cell_m;
    fallback.origin_m = seg.floor.min_m;
    fallback.width = static_cast<int>((seg.floor.max_m.x() - seg.floor.min_m.x()) / fallback.resolution_m) + 1;
    fallback.height = static_cast<int>((seg.floor.max_m.y() - seg.floor.min_m.y()) / fallback.resolution_m) + 1;
    fallback.cells.assign(static_cast<std::size_t>(fallback.width) * static_cast<std::size_t>(fallback.height),
                          CellState::Free);
  }
  const OccupancyGrid& grid = st.floor_plan ? *st.floor_plan : fallback;
  const auto solids = footprint_solids(net, st);
  // Free: seen free, off the solids; with a border of unknown around the grid.
  cv::Mat1b free(grid.height + 2, grid.width + 2, uchar{0}), unoccupied(grid.height, grid.width, uchar{255});
  for (int r = 0; r < grid.height; ++r)
    for (int c = 0; c < grid.width; ++c) {
      free(r + 1, c + 1) = grid.at(c, r) == CellState::Free ? 255 : 0;
      unoccupied(r, c) = grid.at(c, r) == CellState::Occupied ? 0 : 255;
    }
  cv::Mat1b inner = free(cv::Rect(1, 1, grid.width, grid.height));
  clear_solids(inner, grid, solids);
  clear_solids(unoccupied, grid, solids);
  // Where the robot stood: the floor under it is out of the scanner's
  // sight, so only what is occupied counts there; and it stood there, so
  // its half-width is room enough (no margin).
  if (!st.known_poses.empty()) {
    const cv::Mat1f room = clearance_m(unoccupied, grid.resolution_m);
    for (const auto& pose : st.known_poses) {
      const Eigen::Vector2i c = grid.cell_of(pose.head<2>());
      if (grid.contains(c.x(), c.y()) && room(c.y(), c.x()) >= st.robot_half_width_m) return pose;
    }
  }
  // The largest region with room for the robot, at its clearest point.
  const cv::Mat1f room = clearance_m(free, grid.resolution_m)(cv::Rect(1, 1, grid.width, grid.height));
  cv::Mat1b fits;
  cv::compare(room, need, fits, cv::CMP_GE);
  cv::Mat1i labels, stats;
  cv::Mat centroids;
  const int n = cv::connectedComponentsWithStats(fits, labels, stats, centroids, 8, CV_32S);
  int largest = 0;
  for (int k = 1; k < n; ++k)
    if (largest == 0 || stats(k, cv::CC_STAT_AREA) > stats(largest, cv::CC_STAT_AREA)) largest = k;
  if (largest == 0) {
    double most = 0;
    cv::Point at(0, 0);
    cv::minMaxLoc(room, nullptr, &most, nullptr, &at);
    const Eigen::Vector2d p = grid.center(at.x, at.y);
    char msg[384];
    std::snprintf(msg, sizeof msg,
                  "robot start: no free place on the floor plan with %.2f m clearance (robot_half_width_m %.2f + "
                  "robot_margin_m %.2f) from walls, doors, stairs, obstacles and unknown space%s; the most is "
                  "%.2f m at (%.2f, %.2f)",
                  need, st.robot_half_width_m, st.robot_margin_m, st.known_poses.empty() ? "" : ", nor at any scan pose",
                  std::max(0.0, most), p.x(), p.y());
    throw NoRobotStart(msg);
  }
  cv::Point best(-1, -1);
  for (int r = 0; r < grid.height; ++r)
    for (int c = 0; c < grid.width; ++c)
      if (labels(r, c) == largest && (best.x < 0 || room(r, c) > room(best.y, best.x))) best = {c, r};
  const Eigen::Vector2d p = grid.center(best.x, best.y);
  // Facing the nearest door.
  double yaw = 0.0, nearest = std::numeric_limits<double>::infinity();
  for (const auto& d : seg.doors)
    if ((d.center_m - p).norm() < nearest) {
      nearest = (d.center_m - p).norm();
      yaw = std::atan2(d.center_m.y() - p.y(), d.center_m.x() - p.x());
    }
  return {p.x(), p.y(), yaw};
}

std::string world_yaml(const SemanticNet& net, const ExportSettings& st) {
  const auto& seg = net.segmentation();
  std::ostringstream o;
  o << "# Generated by rise-semantic from a registered cloud (sim/README.md \"World file v1\").\n";
  o << "world: " << st.world_name << "\n";
  o << "ground: {friction: 1.0}\n";
  const Eigen::Vector3d start = robot_start(net, st);
  o << "robot_start: {xy_m: [" << num(start.x()) << ", " << num(start.y()) << "], yaw_deg: " << deg(start.z()) << "}\n";
  const auto walls = net.of_kind(EntityKind::Wall);
  if (!walls.empty()) {
    o << "walls:\n";
    for (const int id : walls) {
      const Wall& w = seg.walls[static_cast<std::size_t>(net.entity(id).index)];
      o << "  - {name: " << net.entity(id).name << ", from: [" << num(w.from_m.x()) << ", " << num(w.from_m.y())
        << "], to: [" << num(w.to_m.x()) << ", " << num(w.to_m.y()) << "], height: " << num(w.height_m)
        << ", thickness: " << num(w.thickness_m);
      if (!w.openings.empty()) {
        o << ", openings: [";
        for (std::size_t k = 0; k < w.openings.size(); ++k)
          o << (k ? ", " : "") << "{at_m: " << num(w.openings[k].at_m) << ", width_m: " << num(w.openings[k].width_m)
            << ", height_m: " << num(w.openings[k].height_m) << "}";
        o << "]";
      }
      o << "}\n";
    }
  }
  std::vector<int> panels;
  for (const int id : net.of_kind(EntityKind::Door))
    if (seg.doors[static_cast<std::size_t>(net.entity(id).index)].panel) panels.push_back(id);
  if (!panels.empty()) {
    o << "doors:\n";
    for (const int id : panels) {
      const Panel p = panel_of(seg.doors[static_cast<std::size_t>(net.entity(id).index)]);
      o << "  - {name: " << net.entity(id).name << ", hinge: [" << num(p.hinge.x()) << ", " << num(p.hinge.y())
        << "], width: " << num(p.width_m) << ", height: " << num(p.height_m) << ", thickness: " << num(st.door_thickness_m)
        << ", yaw_deg: " << deg(p.yaw_rad) << ", open_deg_max: " << num(st.door_open_max_deg)
        << ", break_torque_nm: " << num(st.door_break_torque_nm) << ", mass_kg: " << num(st.door_mass_kg) << "}\n";
    }
  }
  const auto stairs = net.of_kind(EntityKind::Stairs);
  if (!stairs.empty()) {
    o << "stairs:\n";
    for (const int id : stairs) {
      const Stairs& s = seg.stairs[static_cast<std::size_t>(net.entity(id).index)];
      o << "  - {name: " << net.entity(id).name << ", start: [" << num(s.start_m.x()) << ", " << num(s.start_m.y())
        << "], yaw_deg: " << deg(s.yaw_rad) << ", steps: " << s.steps << ", riser_m: " << num(s.riser_m)
        << ", tread_m: " << num(s.tread_m) << ", width_m: " << num(s.width_m) << ", landing_m: " << num(s.landing_m) << "}\n";
    }
  }
  const auto obstacles = net.of_kind(EntityKind::Obstacle);
  if (!obstacles.empty()) {
    o << "props:\n";
    for (const int id : obstacles) {
      const Obstacle& b = seg.obstacles[static_cast<std::size_t>(net.entity(id).index)];
      o << "  - {name: " << net.entity(id).name << ", kind: obstacle, center_m: [" << num(b.center_m.x()) << ", "
        << num(b.center_m.y()) << ", " << num(b.center_m.z() - seg.floor.height_m) << "], size_m: [" << num(b.size_m.x())
        << ", " << num(b.size_m.y()) << ", " << num(b.size_m.z()) << "], yaw_deg: " << deg(b.yaw_rad) << "}\n";
    }
  }
  if (seg.ceiling.found) {
    const auto& c = seg.ceiling;
    o << "ceiling: {height_m: " << num(c.height_m - seg.floor.height_m) << ", thickness_m: " << num(st.ceiling_thickness_m)
      << ", min: [" << num(c.min_m.x()) << ", " << num(c.min_m.y()) << "], max: [" << num(c.max_m.x()) << ", "
      << num(c.max_m.y()) << "]}\n";
  }
  return o.str();
}

std::string sdf_world(const SemanticNet& net, const ExportSettings& st) {
  std::ostringstream o;
  o << "<?xml version=\"1.0\"?>\n<sdf version=\"1.6\">\n  <world name=\"" << st.world_name << "\">\n";
  o << "    <gravity>0 0 -9.81</gravity>\n";
  o << "    <light type=\"directional\" name=\"sun\">\n      <cast_shadows>true</cast_shadows>\n"
       "      <pose>0 0 10 0 0 0</pose>\n      <diffuse>0.8 0.8 0.8 1</diffuse>\n"
       "      <direction>-0.5 0.1 -0.9</direction>\n    </light>\n";
  o << "    <model name=\"ground_plane\">\n      <static>true</static>\n      <pose>0 0 "
    << num(net.segmentation().floor.height_m) << " 0 0 0</pose>\n      <link name=\"link\">\n"
       "        <collision name=\"collision\"><geometry><plane><normal>0 0 1</normal><size>100 100</size></plane></geometry></collision>\n"
       "        <visual name=\"visual\"><geometry><plane><normal>0 0 1</normal><size>100 100</size></plane></geometry></visual>\n"
       "      </link>\n    </model>\n";
  int k = 0;
  for (const auto& b : model_boxes(net, st)) {
    if (b.kind == "floor") continue;  // the ground plane
    const std::string size = num(b.size_m.x()) + " " + num(b.size_m.y()) + " " + num(b.size_m.z());
    o << "    <model name=\"" << b.name << "_" << k++ << "\">\n      <static>true</static>\n"
      << "      <pose>" << num(b.center_m.x()) << " " << num(b.center_m.y()) << " " << num(b.center_m.z()) << " 0 0 "
      << num(b.yaw_rad) << "</pose>\n      <link name=\"link\">\n"
      << "        <collision name=\"collision\"><geometry><box><size>" << size << "</size></box></geometry></collision>\n"
      << "        <visual name=\"visual\"><geometry><box><size>" << size << "</size></box></geometry></visual>\n"
      << "      </link>\n    </model>\n";
  }
  o << "  </world>\n</sdf>\n";
  return o.str();
}

std::string obj_mesh(const SemanticNet& net, const ExportSettings& st) {
  std::ostringstream o;
  o << "# rise-semantic environment model: one box per solid, metres, z up\n";
  // Quads of the corner numbering in corners(): bit 0 x, bit 1 y, bit 2 z; outward normals.
  static constexpr int kFaces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  int base = 1, k = 0;
  for (const auto& b : model_boxes(net, st)) {
    o << "o " << b.name << "_" << k++ << "\ng " << b.kind << "\n";
    for (const auto& c : corners(b)) o << "v " << num(c.x()) << " " << num(c.y()) << " " << num(c.z()) << "\n";
    for (const auto& f : kFaces)
      o << "f " << base + f[0] << " " << base + f[1] << " " << base + f[2] << " " << base + f[3] << "\n";
    base += 8;
  }
  return o.str();
}

namespace {

cv::Scalar bgr(const unsigned char (&c)[3]) { return cv::Scalar(c[0], c[1], c[2]); }
cv::Vec3b vec(const unsigned char (&c)[3]) { return cv::Vec3b(c[0], c[1], c[2]); }

// The map without its labels and legend, and where things are on it.
struct BaseMap {
  cv::Mat3b img;
  MapLayout layout;
  double text_scale = 0.5;
};

BaseMap draw_base(const SemanticNet& net, const Cloud* cloud, const ExportSettings& st, const std::string& what) {
  const auto& seg = net.segmentation();
  const auto boxes = model_boxes(net, st);
  BaseMap m;
  MapLayout& l = m.layout;
  Eigen::Vector2d lo = seg.floor.min_m, hi = seg.floor.max_m;
  for (const auto& b : boxes)
    for (const auto& c : corners(b)) {
      lo = lo.cwiseMin(c.head<2>());
      hi = hi.cwiseMax(c.head<2>());
    }
  l.min_m = lo - Eigen::Vector2d(0.5, 0.5);
  l.max_m = hi + Eigen::Vector2d(0.5, 0.5);
  const double k = l.px_per_m = st.map_px_per_m;
  l.cols = static_cast<int>((l.max_m.x() - l.min_m.x()) * k) + 1;
  l.rows = static_cast<int>((l.max_m.y() - l.min_m.y()) * k) + 1;
  if (l.cols > 20000 || l.rows > 20000)
    throw std::runtime_error(what + ": map too large (" + std::to_string(l.cols) + " x " + std::to_string(l.rows) + " px)");
  m.text_scale = std::clamp(k / 100.0, 0.35, 1.0);
  std::shared_ptr<const OccupancyGrid> plan = st.floor_plan;
  if (!plan && cloud) plan = std::make_shared<OccupancyGrid>(floor_plan_of(*cloud, seg, st));
  m.img = cv::Mat3b(l.rows, l.cols, vec(plan ? map_colour::kUnknown : map_colour::kFree));
  if (plan)
    for (int r = 0; r < l.rows; ++r)
      for (int c = 0; c < l.cols; ++c) {
        const Eigen::Vector2i cell = plan->cell_of({l.min_m.x() + (c + 0.5) / k, l.max_m.y() - (r + 0.5) / k});
        if (!plan->contains(cell.x(), cell.y())) continue;
        const CellState v = plan->at(cell.x(), cell.y());
        if (v != CellState::Unknown) m.img(r, c) = vec(v == CellState::Free ? map_colour::kFree : map_colour::kOccupied);
      }
  const auto px = [&](const Eigen::Vector2d& p) {
    return cv::Point(static_cast<int>((p.x() - l.min_m.x()) * k), static_cast<int>((l.max_m.y() - p.y()) * k));
  };
  const auto fill = [&](const ModelBox& b, const cv::Scalar& colour) {
    const auto c = corners(b);
    std::vector<cv::Point> poly = {px(c[0].head<2>()), px(c[1].head<2>()), px(c[3].head<2>()), px(c[2].head<2>())};
    cv::fillConvexPoly(m.img, poly, colour, cv::LINE_8);
    return poly;
  };
  for (const auto& b : boxes) {
    if (b.kind == "stairs") {
      const auto poly = fill(b, bgr(map_colour::kStairs));
      cv::polylines(m.img, poly, true, cv::Scalar(140, 60, 0), 1, cv::LINE_8);
    } else if (b.kind == "obstacle") {
      fill(b, bgr(map_colour::kObstacle));
    }
  }
  for (const auto& b : boxes)
    if (b.kind == "wall") fill(b, bgr(map_colour::kWall));
  for (const auto& d : seg.doors) {
    const Eigen::Vector2d dir(std::cos(d.yaw_rad), std::sin(d.yaw_rad));
    cv::line(m.img, px(d.center_m - dir * d.width_m / 2), px(d.center_m + dir * d.width_m / 2), bgr(map_colour::kDoor),
             std::max(2, static_cast<int>(0.06 * k)), cv::LINE_8);
  }
  return m;
}

// "door_3" → "d3", "wall_a_step_1" → "w1".
std::string abbreviation(const std::string& name) {
  std::size_t digits = name.size();
  while (digits > 0 && std::isdigit(static_cast<unsigned char>(name[digits - 1]))) --digits;
  return name.empty() ? name : name.substr(0, 1) + name.substr(digits);
}

struct LegendItem {
  const unsigned char* colour;  // none: text only
  std::string text;
};

std::vector<LegendItem> legend_items(const SemanticNet& net, const ExportSettings& st) {
  const auto& seg = net.segmentation();
  return {
      {nullptr, st.world_name + "  floor " + num(seg.floor.height_m) + " m  ceiling " +
                    (seg.ceiling.found ? num(seg.ceiling.height_m) + " m" : "-")},
      {map_colour::kFree, "free"},         {map_colour::kUnknown, "unknown"}, {map_colour::kOccupied, "occupied"},
      {map_colour::kWall, "wall"},         {map_colour::kDoor, "door"},       {map_colour::kStairs, "stairs"},
      {map_colour::kObstacle, "obstacle"}};
}

// A nice round length for the scale bar: about a fifth of the map's width.
double scale_length_m(double width_m) {
  double best = 0.1;
  for (const double v : {0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0})
    if (v <= width_m / 5) best = v;
  return best;
}

struct LegendGeometry {
  int line_h = 0, swatch = 0, pad = 0;
  std::vector<cv::Point> at;  // each item's top-left, relative to the legend's box
  cv::Size size;
};

LegendGeometry legend_geometry(const std::vector<LegendItem>& items, double scale, int max_width) {
  LegendGeometry g;
  int baseline = 0;
  const cv::Size m = cv::getTextSize("Mg", cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline);
  g.line_h = m.height + baseline + 4;
  g.swatch = m.height + 2;
  g.pad = 4;
  int x = g.pad, y = g.pad, width = 0;
  for (std::size_t i = 0; i < items.size(); ++i) {
    const int w = cv::getTextSize(items[i].text, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline).width +
                  (items[i].colour ? g.swatch + 4 : 0);
    // The title on a line of its own; the swatches wrap.
    if (x > g.pad && (i == 1 || x + w > max_width)) {
      x = g.pad;
      y += g.line_h;
    }
    g.at.emplace_back(x, y);
    width = std::max(width, x + w + g.pad);
    x += w + 12;
  }
  g.size = {width, y + 2 * g.line_h + g.pad};  // and the scale bar's line
  return g;
}

// Drawn on: neither free nor unknown.
cv::Mat1b drawn_mask(const cv::Mat3b& img) {
  cv::Mat1b drawn(img.rows, img.cols, uchar{0});
  for (int r = 0; r < img.rows; ++r)
    for (int c = 0; c < img.cols; ++c)
      drawn(r, c) = img(r, c) != vec(map_colour::kFree) && img(r, c) != vec(map_colour::kUnknown);
  return drawn;
}

void place_labels(const SemanticNet& net, const cv::Mat1b& drawn, MapLayout& l, double scale) {
  cv::Mat1i sum;
  cv::integral(drawn, sum, CV_32S);
  const auto cover = [&](const cv::Rect& b) {
    return sum(b.y + b.height, b.x + b.width) - sum(b.y, b.x + b.width) - sum(b.y + b.height, b.x) + sum(b.y, b.x);
  };
  std::vector<cv::Rect> taken = {cv::Rect(l.legend_x, l.legend_y, l.legend_width, l.legend_height)};
  const cv::Rect image(0, 0, drawn.cols, drawn.rows);
  // Doors and stairs first, then obstacles, then walls.
  const auto rank = [](EntityKind k) {
    return k == EntityKind::Door ? 0 : k == EntityKind::Stairs ? 1 : k == EntityKind::Obstacle ? 2 : 3;
  };
  std::vector<const Entity*> order;
  for (const auto& e : net.entities())
    if (e.kind == EntityKind::Wall || e.kind == EntityKind::Door || e.kind == EntityKind::Stairs ||
        e.kind == EntityKind::Obstacle)
      order.push_back(&e);
  std::stable_sort(order.begin(), order.end(), [&](const Entity* a, const Entity* b) { return rank(a->kind) < rank(b->kind); });
  for (const Entity* e : order) {
    const cv::Point a(static_cast<int>((e->position_m.x() - l.min_m.x()) * l.px_per_m),
                      static_cast<int>((l.max_m.y() - e->position_m.y()) * l.px_per_m));
    std::optional<MapLabel> best;
    double best_cost = std::numeric_limits<double>::infinity();
    for (const std::string& text : {e->name, abbreviation(e->name)}) {
      int baseline = 0;
      const cv::Size t = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline);
      const int w = t.width + 2, h = t.height + baseline + 2;
      // Around the entity, near first: right, left, above, below, the corners; then farther.
      for (const int d : {4, 4 + h, 4 + 3 * h}) {
        const cv::Point offsets[] = {{d, -h / 2},      {-d - w, -h / 2}, {-w / 2, -d - h}, {-w / 2, d},
                                     {d, -d - h},      {-d - w, -d - h}, {d, d},           {-d - w, d}};
        for (const auto& o : offsets) {
          const cv::Rect box(a + o, cv::Size(w, h));
          if ((box & image) != box) continue;
          bool clear = true;
          for (const auto& r : taken) clear = clear && (box & r).empty();
          if (!clear) continue;
          // What it hides, the distance from its entity, and abbreviating, all cost.
          const double cost = static_cast<double>(cover(box)) / (w * h) + 0.02 * d / h + (text == e->name ? 0.0 : 0.3);
          if (cost < best_cost) {
            best_cost = cost;
            best = MapLabel{e->id, text, box.x, box.y, w, h};
          }
        }
      }
    }
    if (!best) continue;
    taken.emplace_back(best->x, best->y, best->width, best->height);
    l.labels.push_back(*best);
  }
}

// Labels, legend and scale bar laid out on the base map; the legend's own layout.
LegendGeometry lay_out(const SemanticNet& net, const std::vector<LegendItem>& items, BaseMap& m) {
  MapLayout& l = m.layout;
  const LegendGeometry g = legend_geometry(items, m.text_scale, std::max(80, l.cols - 8));
  l.scale_bar_m = scale_length_m(l.max_m.x() - l.min_m.x());
  const int bar_px = static_cast<int>(std::lround(l.scale_bar_m * l.px_per_m));
  int baseline = 0;
  const int bar_w = bar_px + 6 + cv::getTextSize(num(l.scale_bar_m) + " m", cv::FONT_HERSHEY_SIMPLEX, m.text_scale, 1, &baseline).width;
  l.legend_width = std::min(std::max(g.size.width, 2 * g.pad + bar_w), l.cols);
  l.legend_height = std::min(g.size.height, l.rows);
  // The corner with the least drawn on it.
  const cv::Mat1b drawn = drawn_mask(m.img);
  int best = -1;
  for (const auto& [x, y] : {std::pair{2, l.rows - l.legend_height - 2}, std::pair{l.cols - l.legend_width - 2, l.rows - l.legend_height - 2},
                             std::pair{2, 2}, std::pair{l.cols - l.legend_width - 2, 2}}) {
    const cv::Rect r = cv::Rect(x, y, l.legend_width, l.legend_height) & cv::Rect(0, 0, l.cols, l.rows);
    const int busy = cv::countNonZero(drawn(r));
    if (best < 0 || busy < best) {
      best = busy;
      l.legend_x = r.x;
      l.legend_y = r.y;
    }
  }
  l.scale_bar_x0 = l.legend_x + g.pad;
  l.scale_bar_x1 = l.scale_bar_x0 + bar_px;
  l.scale_bar_y = l.legend_y + g.size.height - g.pad - g.line_h / 2;
  place_labels(net, drawn, l, m.text_scale);
  return g;
}

}  // namespace

MapLayout map_layout(const SemanticNet& net, const Cloud* cloud, const ExportSettings& st) {
  BaseMap m = draw_base(net, cloud, st, "map");
  lay_out(net, legend_items(net, st), m);
  return m.layout;
}

void write_map_png(const std::string& path, const SemanticNet& net, const Cloud* cloud, const ExportSettings& st) {
  BaseMap m = draw_base(net, cloud, st, path);
  const auto items = legend_items(net, st);
  const LegendGeometry g = lay_out(net, items, m);
  const MapLayout& l = m.layout;
  const double scale = m.text_scale;
  const auto text = [&](const std::string& s, cv::Point at, const cv::Scalar& colour) {
    int baseline = 0;
    at.y += cv::getTextSize(s, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline).height;
    cv::putText(m.img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, colour, 1, cv::LINE_AA);
  };
  for (const auto& lab : l.labels) {
    const EntityKind kind = net.entity(lab.entity).kind;
    const cv::Scalar colour = kind == EntityKind::Door ? cv::Scalar(0, 110, 0)
                              : kind == EntityKind::Stairs ? cv::Scalar(140, 60, 0)
                              : kind == EntityKind::Obstacle ? cv::Scalar(0, 40, 170)
                                                             : cv::Scalar(0, 0, 0);
    cv::rectangle(m.img, cv::Rect(lab.x, lab.y, lab.width, lab.height), cv::Scalar(255, 255, 255), cv::FILLED);
    text(lab.text, {lab.x + 1, lab.y + 1}, colour);
  }
  // The legend: a white box, the title, the swatches, the scale bar.
  const cv::Rect box(l.legend_x, l.legend_y, l.legend_width, l.legend_height);
  cv::rectangle(m.img, box, cv::Scalar(255, 255, 255), cv::FILLED);
  cv::rectangle(m.img, box, cv::Scalar(0, 0, 0), 1);
  for (std::size_t i = 0; i < items.size(); ++i) {
    cv::Point at(l.legend_x + g.at[i].x, l.legend_y + g.at[i].y);
    if (items[i].colour) {
      const cv::Rect sw(at, cv::Size(g.swatch, g.swatch));
      cv::rectangle(m.img, sw, cv::Scalar(items[i].colour[0], items[i].colour[1], items[i].colour[2]), cv::FILLED);
      cv::rectangle(m.img, sw, cv::Scalar(0, 0, 0), 1);
      at.x += g.swatch + 4;
    }
    text(items[i].text, at, cv::Scalar(0, 0, 0));
  }
  cv::line(m.img, {l.scale_bar_x0, l.scale_bar_y}, {l.scale_bar_x1, l.scale_bar_y}, cv::Scalar(0, 0, 0), 2);
  for (const int x : {l.scale_bar_x0, l.scale_bar_x1})
    cv::line(m.img, {x, l.scale_bar_y - 4}, {x, l.scale_bar_y + 4}, cv::Scalar(0, 0, 0), 1);
  text(num(l.scale_bar_m) + " m", {l.scale_bar_x1 + 6, l.scale_bar_y - g.line_h / 2 + 2}, cv::Scalar(0, 0, 0));
  if (!cv::imwrite(path, m.img)) throw std::runtime_error(path + ": cannot write the PNG map");
}

void write_text_file(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error(path + ": cannot open for writing");
  out << text;
  if (!out.flush()) throw std::runtime_error(path + ": write failed");
}

}  // namespace rise::semantic
