#pragma once

// Found entities against a world file's: walls (centre lines, 5 cm and
// 2°), doors (10 cm), stairs (step count, riser and tread within 1 cm).

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "semantic/segmentation.hpp"
#include "sim/world_description.hpp"

namespace rise::semantic::testing {

struct Segment2 {
  Eigen::Vector2d a, b;
  double length() const { return (b - a).norm(); }
  Eigen::Vector2d dir() const { return (b - a).normalized(); }
};

inline Eigen::Vector2d v2(const std::array<double, 2>& p) { return {p[0], p[1]}; }

/// How much of `s` (m) lies on the segments of `others` that run along it
/// within angle_rad and offset_m (both their ends that close to s's line).
inline double covered_m(const Segment2& s, const std::vector<Segment2>& others, double offset_m, double angle_rad) {
  const Eigen::Vector2d d = s.dir(), n(-d.y(), d.x());
  std::vector<std::pair<double, double>> spans;
  for (const auto& o : others) {
    if (std::abs(o.dir().dot(n)) > std::sin(angle_rad)) continue;
    if (std::abs(n.dot(o.a - s.a)) > offset_m || std::abs(n.dot(o.b - s.a)) > offset_m) continue;
    const double u = d.dot(o.a - s.a), v = d.dot(o.b - s.a);
    spans.push_back({std::max(0.0, std::min(u, v)), std::min(s.length(), std::max(u, v))});
  }
  std::sort(spans.begin(), spans.end());
  double sum = 0, end = 0;
  for (const auto& [u, v] : spans) {
    if (v <= u || v <= end) continue;
    sum += v - std::max(u, end);
    end = v;
  }
  return sum;
}

struct WallScore {
  int truth = 0, found = 0, recalled = 0, precise = 0;
  double precision() const { return found ? static_cast<double>(precise) / found : 0.0; }
  double recall() const { return truth ? static_cast<double>(recalled) / truth : 0.0; }
  std::string report;
};

/// A truth wall is recalled when found walls within 5 cm and 2° cover all
/// of it but 10 cm; a found wall is precise when truth walls cover it so.
inline WallScore score_walls(const std::vector<sim::Wall>& truth, const std::vector<Wall>& found,
                             double offset_m = 0.05, double angle_rad = 2.0 * M_PI / 180.0, double slack_m = 0.1) {
  std::vector<Segment2> t, f;
  for (const auto& w : truth) t.push_back({v2(w.from_m), v2(w.to_m)});
  for (const auto& w : found) f.push_back({w.from_m, w.to_m});
  WallScore s;
  s.truth = static_cast<int>(t.size());
  s.found = static_cast<int>(f.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    const bool ok = covered_m(t[i], f, offset_m, angle_rad) >= t[i].length() - slack_m;
    s.recalled += ok;
    if (!ok) s.report += "missed " + truth[i].name + "; ";
  }
  for (const auto& w : f) {
    const bool ok = covered_m(w, t, offset_m, angle_rad) >= w.length() - slack_m;
    s.precise += ok;
    if (!ok)
      s.report += "spurious (" + std::to_string(w.a.x()) + "," + std::to_string(w.a.y()) + ")-(" +
                  std::to_string(w.b.x()) + "," + std::to_string(w.b.y()) + "); ";
  }
  return s;
}

/// A door of the world file: the middle of its clear gap, its width and height.
struct TruthDoor {
  std::string name;
  Eigen::Vector2d center;
  double width_m, height_m;
};

/// Openings in walls, and hinged doors (whose panel overlaps the walls
/// beside it by half their thickness each side and hangs 1 cm up).
inline std::vector<TruthDoor> truth_doors(const sim::WorldDescription& w) {
  std::vector<TruthDoor> out;
  for (const auto& wall : w.walls) {
    const Eigen::Vector2d a = v2(wall.from_m), d = (v2(wall.to_m) - a).normalized();
    for (const auto& o : wall.openings)
      out.push_back({wall.name, a + d * (o.at_m + o.width_m / 2), o.width_m, o.height_m});
  }
  for (const auto& door : w.doors) {
    const Eigen::Vector2d d(std::cos(door.yaw_rad), std::sin(door.yaw_rad));
    double thickness = 0.0;
    for (const auto& wall : w.walls)
      for (const auto& end : {wall.from_m, wall.to_m})
        if ((v2(end) - v2(door.hinge_m)).norm() < 0.3) thickness = wall.thickness_m;
    out.push_back({door.name, v2(door.hinge_m) + d * door.width_m / 2, door.width_m - thickness, door.height_m + 0.01});
  }
  return out;
}

}  // namespace rise::semantic::testing
