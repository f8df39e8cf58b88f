// grid_render: a debug program to look at 2D maps and at the truth files
// drawn over them (tests/data/buildings/README.md). Not installed.
//
//   grid_render IN OUT.png [--image PGM] [--res M] [--region X0 Y0 X1 Y1]
//               [--px N] [--truth FILE.json] [--dump GRID.pgm] [--detect]
//               [--walls] [--set SETTING=VALUE]...
//
// IN is a map_server .yaml or a CARMEN log. Free cells white, occupied
// black, unknown grey; a thin line every metre, a darker one with its
// coordinate every 5 m; truth walls red, doors green (a bar as wide as the
// door, across the wall). --dump writes the grid itself as a map_server
// PGM (0 occupied, 254 free, 205 unknown; bottom row first in y) and prints
// its origin, for scripts that measure on it. --detect runs
// segment_floor_plan on the grid and draws its walls over it, blue where
// they match a truth wall and magenta where not, its doors as orange bars,
// and prints the score against --truth and the unmatched pieces over 0.3 m;
// --walls lists every wall it found.

#include <json/json.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <string>

#include "semantic/floor_plan.hpp"
#include "semantic/occupancy_grid.hpp"
#include "tests/semantic/building_truth.hpp"

using rise::semantic::CellState;
using rise::semantic::OccupancyGrid;

namespace {

template <class ToPx>
void draw_detections(cv::Mat& img, const OccupancyGrid& g, const std::string& truth_file,
                     const rise::semantic::FloorPlanSettings& settings, bool list_walls, const ToPx& to_px) {
  using namespace rise::semantic;
  using testing::detail::Segment;
  const Segmentation seg = segment_floor_plan(g, settings);
  testing::BuildingTruth truth;
  if (!truth_file.empty()) truth = testing::read_building_truth(truth_file);
  std::vector<Segment> expected;
  for (const auto& t : truth.walls)
    if (const auto c = testing::detail::clipped(t, truth.region)) expected.push_back(*c);
  std::vector<std::vector<std::pair<double, double>>> covered(expected.size());
  for (const Wall& w : seg.walls) {
    const Eigen::Vector2d u = w.direction();
    std::vector<Segment> parts;
    double at = 0;
    for (const Opening& o : w.openings) {
      parts.push_back({w.from_m + at * u, w.from_m + o.at_m * u});
      at = o.at_m + o.width_m;
    }
    parts.push_back({w.from_m + at * u, w.to_m});
    for (const Segment& d : parts) {
      cv::line(img, to_px(d.first.x(), d.first.y()), to_px(d.second.x(), d.second.y()), {255, 0, 255}, 2);
      const auto c = testing::detail::clipped(d, truth.region);
      if (!c) continue;
      const double len = (c->second - c->first).norm();
      std::vector<std::pair<double, double>> own;
      for (std::size_t i = 0; i < expected.size(); ++i) {
        const auto o = testing::detail::overlap_on_truth(*c, expected[i]);
        if (!o) continue;
        covered[i].push_back(*o);
        const Eigen::Vector2d tu = (expected[i].second - expected[i].first).normalized();
        const Eigen::Vector2d a = expected[i].first + o->first * tu, b = expected[i].first + o->second * tu;
        cv::line(img, to_px(a.x(), a.y()), to_px(b.x(), b.y()), {255, 120, 0}, 2);
        const Eigen::Vector2d v = (c->second - c->first) / len;
        own.emplace_back(std::clamp(std::min(v.dot(a - c->first), v.dot(b - c->first)), 0.0, len),
                         std::clamp(std::max(v.dot(a - c->first), v.dot(b - c->first)), 0.0, len));
      }
      const double miss = len - testing::detail::union_length(own);
      if (miss > 0.3)
        std::printf("unmatched detection %.1f of %.1f m: (%.2f, %.2f) - (%.2f, %.2f)\n", miss, len, c->first.x(),
                    c->first.y(), c->second.x(), c->second.y());
    }
  }
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const double len = (expected[i].second - expected[i].first).norm();
    const double miss = len - testing::detail::union_length(covered[i]);
    if (miss > 0.3)
      std::printf("uncovered truth %.1f of %.1f m: (%.2f, %.2f) - (%.2f, %.2f)\n", miss, len, expected[i].first.x(),
                  expected[i].first.y(), expected[i].second.x(), expected[i].second.y());
  }
  if (list_walls)
    for (const auto& w : seg.walls)
      std::printf("wall (%.2f, %.2f) - (%.2f, %.2f) thickness %.2f\n", w.from_m.x(), w.from_m.y(), w.to_m.x(),
                  w.to_m.y(), w.thickness_m);
  for (const Door& d : seg.doors) {
    const Eigen::Vector2d t(std::cos(d.yaw_rad), std::sin(d.yaw_rad));
    const Eigen::Vector2d a = d.center_m - d.width_m / 2 * t, b = d.center_m + d.width_m / 2 * t;
    cv::line(img, to_px(a.x(), a.y()), to_px(b.x(), b.y()), {0, 140, 255}, 3);
    std::printf("door (%.2f, %.2f) width %.2f yaw %.1f\n", d.center_m.x(), d.center_m.y(), d.width_m,
                d.yaw_rad * 180 / 3.14159265358979);
  }
  const testing::BuildingScore s = testing::score_building(seg, truth);
  std::printf("walls: precision %.3f recall %.3f (%.1f m found, %.1f m true); doors: precision %.3f recall %.3f "
              "(%d found, %d true, %d matched)\n",
              s.wall_precision, s.wall_recall, s.detected_wall_m, s.truth_wall_m, s.door_precision, s.door_recall,
              s.doors_detected, s.doors_truth, s.doors_matched);
}

}  // namespace

int main(int argc, char** argv) try {
  if (argc < 3) {
    std::cerr << "usage: grid_render IN OUT.png [--image PGM] [--res M] [--region X0 Y0 X1 Y1] [--px N] [--truth F]\n";
    return 2;
  }
  const std::string in = argv[1], out = argv[2];
  std::string image, truth, dump;
  double res = 0.05;
  int px = 2;
  bool region = false, detect = false, list_walls = false;
  rise::semantic::FloorPlanSettings settings;
  const std::map<std::string, double*> knobs = {
      {"door_min_width_m", &settings.door_min_width_m},     {"door_max_width_m", &settings.door_max_width_m},
      {"min_face_length_m", &settings.min_face_length_m},   {"min_wall_length_m", &settings.min_wall_length_m},
      {"free_wall_min_length_m", &settings.free_wall_min_length_m},
      {"max_wall_thickness_m", &settings.max_wall_thickness_m}, {"noise_gap_m", &settings.noise_gap_m},
      {"collinear_offset_m", &settings.collinear_offset_m}, {"min_direction_share", &settings.min_direction_share},
      {"corner_gap_m", &settings.corner_gap_m},             {"door_clearance_m", &settings.door_clearance_m},
      {"door_min_free", &settings.door_min_free},           {"door_jamb_m", &settings.door_jamb_m},
      {"door_min_depth_m", &settings.door_min_depth_m}, {"corner_door_min_depth_m", &settings.corner_door_min_depth_m},     {"minor_direction_share", &settings.minor_direction_share},
      {"minor_wall_min_length_m", &settings.minor_wall_min_length_m},
      {"slant_within_m", &settings.slant_within_m},         {"slant_min_solid", &settings.slant_min_solid},
      {"door_jamb_solid", &settings.door_jamb_solid},       {"angle_tolerance_rad", &settings.angle_tolerance_rad},
      {"straight_share", &settings.straight_share},         {"straight_within_m", &settings.straight_within_m},
      {"trim_keep", &settings.trim_keep}};
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  for (int i = 3; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--image") image = argv[++i];
    else if (a == "--res") res = std::atof(argv[++i]);
    else if (a == "--px") px = std::atoi(argv[++i]);
    else if (a == "--truth") truth = argv[++i];
    else if (a == "--dump") dump = argv[++i];
    else if (a == "--detect") detect = true;
    else if (a == "--walls") list_walls = true;
    else if (a == "--set") {  // --set NAME=VALUE: a FloorPlanSettings field
      const std::string kv = argv[++i];
      const auto k = knobs.find(kv.substr(0, kv.find('=')));
      if (k == knobs.end()) throw std::runtime_error("unknown setting " + kv);
      *k->second = std::atof(kv.substr(kv.find('=') + 1).c_str());
    }
    else if (a == "--region") {
      region = true;
      x0 = std::atof(argv[++i]), y0 = std::atof(argv[++i]), x1 = std::atof(argv[++i]), y1 = std::atof(argv[++i]);
    } else throw std::runtime_error("unknown option " + a);
  }
  const bool ros = in.size() > 5 && in.substr(in.size() - 5) == ".yaml";
  const OccupancyGrid g = ros ? rise::semantic::read_ros_map(in, image)
                              : rise::semantic::grid_from_scans(rise::semantic::read_carmen_log(in), res);
  size_t occ = 0, fre = 0;
  for (auto c : g.cells) occ += c == CellState::Occupied, fre += c == CellState::Free;
  std::printf("%d x %d cells of %.3f m, origin %.3f %.3f, extent %.2f x %.2f m, occupied %zu, free %zu\n", g.width,
              g.height, g.resolution_m, g.origin_m.x(), g.origin_m.y(), g.width * g.resolution_m,
              g.height * g.resolution_m, occ, fre);
  if (!dump.empty()) {
    cv::Mat m(g.height, g.width, CV_8U);
    for (int r = 0; r < g.height; ++r)
      for (int c = 0; c < g.width; ++c) {
        const CellState st = g.at(c, r);
        m.at<uint8_t>(g.height - 1 - r, c) = st == CellState::Occupied ? 0 : st == CellState::Free ? 254 : 205;
      }
    cv::imwrite(dump, m);
  }
  if (!region) {
    x0 = g.origin_m.x(), y0 = g.origin_m.y();
    x1 = x0 + g.width * g.resolution_m, y1 = y0 + g.height * g.resolution_m;
  }
  const double s = px / g.resolution_m;  // pixels per metre
  const int W = static_cast<int>((x1 - x0) * s), H = static_cast<int>((y1 - y0) * s);
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(160, 160, 160));
  auto to_px = [&](double x, double y) { return cv::Point(static_cast<int>((x - x0) * s), static_cast<int>((y1 - y) * s)); };
  for (int v = 0; v < H; ++v)
    for (int u = 0; u < W; ++u) {
      const Eigen::Vector2d p(x0 + (u + 0.5) / s, y1 - (v + 0.5) / s);
      const Eigen::Vector2i c = g.cell_of(p);
      if (!g.contains(c.x(), c.y())) continue;
      const CellState st = g.at(c.x(), c.y());
      if (st == CellState::Free) img.at<cv::Vec3b>(v, u) = {255, 255, 255};
      else if (st == CellState::Occupied) img.at<cv::Vec3b>(v, u) = {0, 0, 0};
    }
  for (int m = static_cast<int>(std::floor(x0)); m <= x1; ++m) {
    const bool five = m % 5 == 0;
    cv::line(img, to_px(m, y0), to_px(m, y1), five ? cv::Scalar(200, 120, 0) : cv::Scalar(240, 200, 150), 1);
    if (five) cv::putText(img, std::to_string(m), to_px(m + 0.05, y1 - 0.6), cv::FONT_HERSHEY_SIMPLEX, 0.4, {200, 60, 0}, 1);
  }
  for (int m = static_cast<int>(std::floor(y0)); m <= y1; ++m) {
    const bool five = m % 5 == 0;
    cv::line(img, to_px(x0, m), to_px(x1, m), five ? cv::Scalar(200, 120, 0) : cv::Scalar(240, 200, 150), 1);
    if (five) cv::putText(img, std::to_string(m), to_px(x0 + 0.1, m + 0.1), cv::FONT_HERSHEY_SIMPLEX, 0.4, {200, 60, 0}, 1);
  }
  if (!truth.empty()) {
    std::ifstream f(truth);
    Json::Value j;
    f >> j;
    int n = 0;
    for (const auto& w : j["walls"]) {
      cv::line(img, to_px(w[0].asDouble(), w[1].asDouble()), to_px(w[2].asDouble(), w[3].asDouble()), {0, 0, 255}, 1);
      cv::putText(img, std::to_string(n++), to_px((w[0].asDouble() + w[2].asDouble()) / 2, (w[1].asDouble() + w[3].asDouble()) / 2),
                  cv::FONT_HERSHEY_PLAIN, 0.8, {0, 0, 200}, 1);
    }
    for (const auto& d : j["doors"]) {
      const double cx = d["center"][0].asDouble(), cy = d["center"][1].asDouble(), h = d["width"].asDouble() / 2;
      const double a = d["wall_angle_deg"].asDouble() * 3.14159265358979 / 180;
      const Eigen::Vector2d t(std::cos(a), std::sin(a));
      cv::line(img, to_px(cx - h * t.x(), cy - h * t.y()), to_px(cx + h * t.x(), cy + h * t.y()), {0, 200, 0}, 3);
      cv::circle(img, to_px(cx, cy), 3, {0, 150, 0}, -1);
    }
  }
  if (detect) draw_detections(img, g, truth, settings, list_walls, to_px);
  cv::imwrite(out, img);
  return 0;
} catch (const std::exception& e) {
  std::cerr << "grid_render: " << e.what() << "\n";
  return 1;
}
