#include "semantic/world_export.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
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

// Distance from p to a box's footprint (0 inside).
double distance_to(const ModelBox& b, const Eigen::Vector2d& p) {
  const double c = std::cos(b.yaw_rad), s = std::sin(b.yaw_rad);
  const Eigen::Vector2d d = p - b.center_m.head<2>();
  const Eigen::Vector2d local(c * d.x() + s * d.y(), -s * d.x() + c * d.y());
  const Eigen::Vector2d q = local.cwiseAbs() - b.size_m.head<2>() / 2;
  return q.cwiseMax(0.0).norm();
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

Eigen::Vector3d robot_start(const SemanticNet& net, const ExportSettings& st) {
  if (st.robot_start) return *st.robot_start;
  const auto& seg = net.segmentation();
  std::vector<ModelBox> solids;
  for (auto& b : model_boxes(net, st))
    if (b.kind != "floor" && b.kind != "ceiling") solids.push_back(b);
  const auto clearance = [&](const Eigen::Vector2d& p) {
    double c = std::numeric_limits<double>::infinity();
    for (const auto& b : solids) c = std::min(c, distance_to(b, p));
    return c;
  };
  const auto on_floor = [&](const Eigen::Vector2d& p) {
    return p.x() > seg.floor.min_m.x() && p.x() < seg.floor.max_m.x() && p.y() > seg.floor.min_m.y() &&
           p.y() < seg.floor.max_m.y();
  };
  for (const auto& d : seg.doors) {
    const Eigen::Vector2d along(std::cos(d.yaw_rad), std::sin(d.yaw_rad)), n(-along.y(), along.x());
    for (const double r : {1.0, 1.5, 2.0, 2.5})
      for (const double side : {1.0, -1.0}) {
        const Eigen::Vector2d p = d.center_m + n * side * r;
        if (!on_floor(p) || clearance(p) < st.robot_clearance_m) continue;
        const Eigen::Vector2d to_door = d.center_m - p;
        return {p.x(), p.y(), std::atan2(to_door.y(), to_door.x())};
      }
  }
  // No door (or none with room in front): the clearest point of a 10 cm grid.
  Eigen::Vector2d best = (seg.floor.min_m + seg.floor.max_m) / 2;
  double best_c = -1;
  for (double x = seg.floor.min_m.x(); x <= seg.floor.max_m.x(); x += 0.1)
    for (double y = seg.floor.min_m.y(); y <= seg.floor.max_m.y(); y += 0.1) {
      const double c = clearance({x, y});
      if (c > best_c) best_c = c, best = {x, y};
    }
  return {best.x(), best.y(), 0.0};
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

void write_map_png(const std::string& path, const SemanticNet& net, const Cloud* cloud, const ExportSettings& st) {
  const auto& seg = net.segmentation();
  const auto boxes = model_boxes(net, st);
  Eigen::Vector2d lo = seg.floor.min_m, hi = seg.floor.max_m;
  for (const auto& b : boxes)
    for (const auto& c : corners(b)) {
      lo = lo.cwiseMin(c.head<2>());
      hi = hi.cwiseMax(c.head<2>());
    }
  lo -= Eigen::Vector2d(0.5, 0.5);
  hi += Eigen::Vector2d(0.5, 0.5);
  const double k = st.map_px_per_m;
  const int cols = static_cast<int>((hi.x() - lo.x()) * k) + 1, rows = static_cast<int>((hi.y() - lo.y()) * k) + 1;
  if (cols > 20000 || rows > 20000) throw std::runtime_error(path + ": map too large (" + std::to_string(cols) + " x " + std::to_string(rows) + " px)");
  cv::Mat3b img(rows, cols, cv::Vec3b(255, 255, 255));
  const auto px = [&](const Eigen::Vector2d& p) {
    return cv::Point(static_cast<int>((p.x() - lo.x()) * k), static_cast<int>((hi.y() - p.y()) * k));
  };
  if (cloud) {
    const double z0 = seg.floor.height_m + 0.05;
    const double z1 = seg.ceiling.found ? seg.ceiling.height_m - 0.05 : std::numeric_limits<double>::infinity();
    for (const auto& p : cloud->points) {
      const cv::Point q = px(p.head<2>().cast<double>());
      if (q.x < 0 || q.y < 0 || q.x >= cols || q.y >= rows) continue;
      if (p.z() < seg.floor.height_m + 0.03) {
        if (img(q) == cv::Vec3b(255, 255, 255)) img(q) = cv::Vec3b(235, 235, 235);  // seen floor
      } else if (p.z() > z0 && p.z() < z1) {
        img(q) = cv::Vec3b(160, 160, 160);  // occupied
      }
    }
  }
  const auto fill = [&](const ModelBox& b, const cv::Scalar& colour) {
    const auto c = corners(b);
    std::vector<cv::Point> poly = {px(c[0].head<2>()), px(c[1].head<2>()), px(c[3].head<2>()), px(c[2].head<2>())};
    cv::fillConvexPoly(img, poly, colour, cv::LINE_AA);
    return poly;
  };
  for (const auto& b : boxes) {
    if (b.kind == "stairs") {
      const auto poly = fill(b, cv::Scalar(230, 160, 90));  // BGR: blue
      cv::polylines(img, poly, true, cv::Scalar(140, 60, 0), 1, cv::LINE_AA);
    } else if (b.kind == "obstacle") {
      fill(b, cv::Scalar(60, 60, 220));
    }
  }
  for (const auto& b : boxes)
    if (b.kind == "wall") fill(b, cv::Scalar(30, 30, 30));
  for (const auto& d : seg.doors) {
    const Eigen::Vector2d dir(std::cos(d.yaw_rad), std::sin(d.yaw_rad));
    cv::line(img, px(d.center_m - dir * d.width_m / 2), px(d.center_m + dir * d.width_m / 2), cv::Scalar(40, 170, 40),
             std::max(2, static_cast<int>(0.06 * k)), cv::LINE_AA);
  }
  const double scale = std::clamp(k / 100.0, 0.35, 1.0);
  for (const auto& e : net.entities()) {
    if (e.kind == EntityKind::Floor || e.kind == EntityKind::Ceiling || e.kind == EntityKind::Step) continue;
    const cv::Scalar colour = e.kind == EntityKind::Door ? cv::Scalar(0, 120, 0)
                              : e.kind == EntityKind::Stairs ? cv::Scalar(140, 60, 0)
                              : e.kind == EntityKind::Obstacle ? cv::Scalar(0, 0, 180)
                                                              : cv::Scalar(90, 90, 90);
    int baseline = 0;
    const cv::Size text = cv::getTextSize(e.name, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline);
    cv::Point at = px(e.position_m.head<2>());
    at.x = std::clamp(at.x + 4, 2, std::max(2, cols - text.width - 2));
    at.y = std::clamp(at.y - 4, text.height + 2, std::max(text.height + 2, rows - 30));
    cv::putText(img, e.name, at, cv::FONT_HERSHEY_SIMPLEX, scale, colour, 1, cv::LINE_AA);
  }
  char legend[96];
  std::snprintf(legend, sizeof legend, "%s  1 m = %.0f px  floor %.2f m  ceiling %s", st.world_name.c_str(), k,
                seg.floor.height_m, seg.ceiling.found ? (num(seg.ceiling.height_m) + " m").c_str() : "-");
  cv::putText(img, legend, cv::Point(5, rows - 6), cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::line(img, cv::Point(5, rows - 24), cv::Point(5 + static_cast<int>(k), rows - 24), cv::Scalar(0, 0, 0), 2);
  if (!cv::imwrite(path, img)) throw std::runtime_error(path + ": cannot write the PNG map");
}

void write_text_file(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error(path + ": cannot open for writing");
  out << text;
  if (!out.flush()) throw std::runtime_error(path + ": write failed");
}

}  // namespace rise::semantic
