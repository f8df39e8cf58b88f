// Stairs and obstacles: what is neither floor, ceiling, wall nor door,
// clustered on the floor plane. A cluster whose height climbs along one
// direction in equal steps is a staircase — the seed paper's "set of
// parallel lines in the same short distance between each other", here the
// riser edges, fitted by least squares over the steps — the rest are boxes.

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

#include "semantic/segmentation_internal.hpp"

namespace rise::semantic::detail {
namespace {

struct Point3 {
  Eigen::Vector2d xy;
  double z;  // above the floor
};

// Sharpness of the points' distribution along direction `theta`: risers
// perpendicular to it pile up in few 1 cm bins.
double sharpness(const std::vector<Point3>& pts, double theta) {
  const Eigen::Vector2d d(std::cos(theta), std::sin(theta));
  std::vector<int> bins;
  double lo = std::numeric_limits<double>::infinity();
  for (const auto& p : pts) lo = std::min(lo, d.dot(p.xy));
  for (const auto& p : pts) {
    const auto k = static_cast<std::size_t>((d.dot(p.xy) - lo) / 0.01);
    if (k >= bins.size()) bins.resize(k + 1, 0);
    ++bins[k];
  }
  double sum = 0;
  for (int b : bins) sum += static_cast<double>(b) * b;
  return sum;
}

// The climb direction (angle of +x): the height gradient, z ≈ g·xy + c
// (least squares), turned so that the risers are sharpest; none when the
// points do not climb.
std::optional<double> climb_direction(const std::vector<Point3>& pts) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (const auto& p : pts) {
    const Eigen::Vector3d row(p.xy.x(), p.xy.y(), 1.0);
    A += row * row.transpose();
    rhs += row * p.z;
  }
  const Eigen::Vector3d g = A.ldlt().solve(rhs);
  if (!g.allFinite() || g.head<2>().norm() < 0.15) return std::nullopt;
  double theta = std::atan2(g.y(), g.x());
  // Coarse then fine search.
  for (const double step : {0.5 * M_PI / 180.0, 0.05 * M_PI / 180.0}) {
    double best = theta, best_v = -1;
    for (int k = -20; k <= 20; ++k) {
      const double t = theta + k * step;
      const double v = sharpness(pts, t);
      if (v > best_v) {
        best_v = v;
        best = t;
      }
    }
    theta = best;
  }
  return theta;
}

struct Top {
  double along, z;
  std::size_t points;
};

// Profile: the top of each 2 cm slice along the climb `d` holding 3 points
// or more; lo: where the points begin along it.
struct Profile {
  double lo = 0;
  std::vector<Top> tops;
  static constexpr double kBin = 0.02;
};

Profile profile_along(const std::vector<Point3>& pts, const Eigen::Vector2d& d) {
  Profile out;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& p : pts) {
    lo = std::min(lo, d.dot(p.xy));
    hi = std::max(hi, d.dot(p.xy));
  }
  out.lo = lo;
  constexpr double kBin = Profile::kBin;
  const auto nb = static_cast<std::size_t>((hi - lo) / kBin) + 1;
  std::vector<std::vector<double>> col(nb);
  for (const auto& p : pts) col[static_cast<std::size_t>((d.dot(p.xy) - lo) / kBin)].push_back(p.z);
  for (std::size_t i = 0; i < nb; ++i)
    if (col[i].size() >= 3)
      out.tops.push_back({lo + (static_cast<double>(i) + 0.5) * kBin, quantile(col[i], 0.95), col[i].size()});
  return out;
}

// Levels: tops within 2 cm of each other holding 20 points or more (a
// riser seen from below is one or two slices: its top edge is the level),
// each the median height of its tops, lowest first.
std::vector<double> levels_of(const std::vector<Top>& tops, const SegmentationSettings& s) {
  std::vector<Top> by_z = tops;
  std::sort(by_z.begin(), by_z.end(), [](const Top& a, const Top& b) { return a.z < b.z; });
  std::vector<std::vector<Top>> groups;
  for (const auto& t : by_z) {
    if (groups.empty() || t.z - groups.back().back().z > 0.02) groups.emplace_back();
    groups.back().push_back(t);
  }
  std::vector<double> levels;
  for (const auto& gr : groups) {
    std::size_t points = 0;
    std::vector<double> z;
    for (const auto& t : gr) {
      points += t.points;
      z.push_back(t.z);
    }
    if (points >= 20 && quantile(z, 0.5) > 0.5 * s.stairs_min_riser_m) levels.push_back(quantile(z, 0.5));
  }
  return levels;
}

// Equal steps: y_k = slope·k + intercept, k = 1..n, least squares.
struct StepFit {
  double slope = 0, intercept = 0;
};

StepFit fit_steps(const std::vector<double>& y) {
  const int n = static_cast<int>(y.size());
  double sk = 0, sy = 0, skk = 0, sky = 0;
  for (int k = 1; k <= n; ++k) {
    sk += k;
    sy += y[static_cast<std::size_t>(k - 1)];
    skk += k * k;
    sky += k * y[static_cast<std::size_t>(k - 1)];
  }
  const double slope = (n * sky - sk * sy) / (n * skk - sk * sk);
  return {slope, (sy - slope * sk) / n};
}

// The stairs' axes: d along the climb, c across it, and the points' extent
// [c0, c1] across.
struct StairAxes {
  Eigen::Vector2d d, c;
  double c0 = 0, c1 = 0;
  double mid() const { return (c0 + c1) / 2; }
};

// Riser k stands where level k begins; its face points (clear of the
// stairs' sides) give its position along the climb. Also where the top
// level ends.
std::vector<double> riser_positions(const std::vector<Point3>& pts, const Profile& profile,
                                    const std::vector<double>& levels, double riser, const StairAxes& axes,
                                    double& last_end) {
  const int n = static_cast<int>(levels.size());
  const double cm = axes.mid();
  std::vector<double> riser_at(static_cast<std::size_t>(n));
  last_end = profile.lo;
  for (int k = 1; k <= n; ++k) {
    const double zk = levels[static_cast<std::size_t>(k - 1)];
    double first = std::numeric_limits<double>::infinity();
    for (const auto& t : profile.tops)
      if (std::abs(t.z - zk) < 0.03) {
        first = std::min(first, t.along);
        if (k == n) last_end = std::max(last_end, t.along);
      }
    const double z_below = k == 1 ? 0.0 : levels[static_cast<std::size_t>(k - 2)];
    std::vector<double> face;
    for (const auto& p : pts) {
      const double a = axes.d.dot(p.xy);
      if (std::abs(a - first) > 0.06 || std::abs(axes.c.dot(p.xy) - cm) > 0.4 * (axes.c1 - axes.c0)) continue;
      if (p.z < z_below + 0.25 * riser || p.z > zk - 0.25 * riser) continue;
      face.push_back(a);
    }
    riser_at[static_cast<std::size_t>(k - 1)] = face.size() >= 5 ? quantile(face, 0.5) : first;
  }
  return riser_at;
}

std::optional<Stairs> fit_stairs(const std::vector<Point3>& pts, const SegmentationSettings& s) {
  if (pts.size() < 200) return std::nullopt;
  const std::optional<double> theta = climb_direction(pts);
  if (!theta) return std::nullopt;
  StairAxes axes;
  axes.d = Eigen::Vector2d(std::cos(*theta), std::sin(*theta));
  axes.c = Eigen::Vector2d(-axes.d.y(), axes.d.x());
  const Profile profile = profile_along(pts, axes.d);
  const std::vector<double> levels = levels_of(profile.tops, s);
  const int n = static_cast<int>(levels.size());
  if (n < s.stairs_min_steps) return std::nullopt;
  const StepFit rise = fit_steps(levels);
  const double riser = rise.slope, b = rise.intercept;
  if (riser < s.stairs_min_riser_m || riser > s.stairs_max_riser_m || std::abs(b) > 0.3 * riser) return std::nullopt;
  for (int k = 1; k <= n; ++k)
    if (std::abs(levels[static_cast<std::size_t>(k - 1)] - (k * riser + b)) > 0.25 * riser) return std::nullopt;
  // Width across the climb.
  std::vector<double> across;
  for (const auto& p : pts) across.push_back(axes.c.dot(p.xy));
  axes.c0 = quantile(across, 0.0);
  axes.c1 = quantile(across, 1.0);
  double last_end = 0;
  const std::vector<double> riser_at = riser_positions(pts, profile, levels, riser, axes, last_end);
  const StepFit run = fit_steps(riser_at);
  const double tread = run.slope;
  const double a1 = run.intercept + tread;  // riser 1
  if (tread < s.stairs_min_tread_m || tread > s.stairs_max_tread_m) return std::nullopt;
  double rss = 0;
  for (int k = 1; k <= n; ++k) {
    const double e = riser_at[static_cast<std::size_t>(k - 1)] - (a1 + (k - 1) * tread);
    rss += e * e;
  }
  Stairs st;
  st.rms_m = std::sqrt(rss / n);
  if (st.rms_m > 0.3 * tread) return std::nullopt;
  st.start_m = axes.d * a1 + axes.c * axes.mid();
  st.yaw_rad = *theta;
  st.steps = n;
  st.riser_m = riser;
  st.tread_m = tread;
  st.width_m = axes.c1 - axes.c0;
  st.landing_m = std::max(0.1, last_end + Profile::kBin / 2 - (a1 + n * tread));
  st.points = static_cast<int>(pts.size());
  return st;
}

Obstacle box_of(const std::vector<Point3>& pts, double floor_z) {
  std::vector<cv::Point2f> xy;
  std::vector<double> z;
  for (const auto& p : pts) {
    xy.emplace_back(static_cast<float>(p.xy.x()), static_cast<float>(p.xy.y()));
    z.push_back(p.z);
  }
  const cv::RotatedRect r = cv::minAreaRect(xy);
  double bottom = quantile(z, 0.01);
  if (bottom < 0.1) bottom = 0.0;  // standing on the floor
  const double top = quantile(z, 0.99);
  Obstacle o;
  o.center_m = {r.center.x, r.center.y, floor_z + (bottom + top) / 2};
  o.size_m = {std::max(0.02f, r.size.width), std::max(0.02f, r.size.height), std::max(0.02, top - bottom)};
  o.yaw_rad = r.angle * M_PI / 180.0;
  o.points = static_cast<int>(pts.size());
  return o;
}

bool oversize(const Obstacle& o, const SegmentationSettings& s) {
  return o.size_m.maxCoeff() > s.obstacle_max_size_m;
}

// Whether the box `o` of points `pts` shuts door `d`: it covers part of
// the door's passage (its gap, out to a door width either side of the
// wall) where hardly any of its points stand lower than a door's top
// (door_min_height_m; higher up, by the lintel, they stop nobody).
bool shuts(const Obstacle& o, const std::vector<Point3>& pts, const Door& d, const SegmentationSettings& s) {
  const Eigen::Vector2d along(std::cos(d.yaw_rad), std::sin(d.yaw_rad)), across(-along.y(), along.x());
  const auto in_passage = [&](const Eigen::Vector2d& xy) {
    return std::abs(along.dot(xy - d.center_m)) < d.width_m / 2 && std::abs(across.dot(xy - d.center_m)) < d.width_m;
  };
  const Eigen::Vector2d ax(std::cos(o.yaw_rad), std::sin(o.yaw_rad)), ay(-ax.y(), ax.x());
  bool covers = false;
  for (double u = -0.5; u <= 0.5 && !covers; u += 0.05)
    for (double v = -0.5; v <= 0.5 && !covers; v += 0.05)
      covers = in_passage(o.center_m.head<2>() + u * o.size_m.x() * ax + v * o.size_m.y() * ay);
  if (!covers) return false;
  int blocking = 0;
  for (const auto& p : pts) blocking += p.z < s.door_min_height_m && in_passage(p.xy) ? 1 : 0;
  return blocking < s.obstacle_min_points;
}

// Clusters of `pts`: connected cells of cell_m after a dilation by a
// `dilate` cells wide disc (scan lines a few cells apart on a far surface
// are one cluster). Clusters in no particular order.
std::vector<std::vector<Point3>> connected(const std::vector<Point3>& pts, double cell, int dilate) {
  if (pts.empty()) return {};
  Eigen::Vector2d lo = pts[0].xy, hi = pts[0].xy;
  for (const auto& p : pts) {
    lo = lo.cwiseMin(p.xy);
    hi = hi.cwiseMax(p.xy);
  }
  check_grid(hi - lo, cell, "what stands on the floor");
  const int nx = static_cast<int>((hi.x() - lo.x()) / cell) + 1, ny = static_cast<int>((hi.y() - lo.y()) / cell) + 1;
  cv::Mat1b image(ny, nx, uchar{0});
  const auto rc = [&](const Eigen::Vector2d& xy) {
    return cv::Point(static_cast<int>((xy.x() - lo.x()) / cell), static_cast<int>((xy.y() - lo.y()) / cell));
  };
  for (const auto& p : pts) image(rc(p.xy)) = 255;
  cv::dilate(image, image, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(dilate, dilate)));
  cv::Mat1i labels;
  const int n = cv::connectedComponents(image, labels, 8, CV_32S);
  std::vector<std::vector<Point3>> clusters(static_cast<std::size_t>(n));
  for (const auto& p : pts) clusters[static_cast<std::size_t>(labels(rc(p.xy)))].push_back(p);
  clusters.erase(clusters.begin());  // the background
  return clusters;
}

// The points outside cells of obstacle_cell_m whose points spread over a
// wall's height (wall_min_tall_m): walls and pillars, not things.
std::vector<Point3> without_tall_columns(const std::vector<Point3>& pts, const SegmentationSettings& s) {
  const double cell = s.obstacle_cell_m;
  const auto key = [&](const Eigen::Vector2d& xy) {
    return std::pair<long long, long long>(static_cast<long long>(std::floor(xy.x() / cell)),
                                           static_cast<long long>(std::floor(xy.y() / cell)));
  };
  std::map<std::pair<long long, long long>, std::pair<double, double>> span;
  for (const auto& p : pts) {
    auto [it, fresh] = span.try_emplace(key(p.xy), p.z, p.z);
    if (!fresh) it->second = {std::min(it->second.first, p.z), std::max(it->second.second, p.z)};
  }
  std::vector<Point3> out;
  for (const auto& p : pts) {
    const auto& [z0, z1] = span.at(key(p.xy));
    if (z1 - z0 < s.wall_min_tall_m) out.push_back(p);
  }
  return out;
}

}  // namespace

void find_stairs_and_obstacles(const Cloud& cloud, const SegmentationSettings& s, const Floor& floor,
                               const Ceiling& ceiling, const std::vector<Wall>& walls,
                               const std::vector<Door>& doors, std::vector<Stairs>& stairs,
                               std::vector<Obstacle>& obstacles, int& dropped) {
  const double z0 = floor.height_m + std::max(0.04, floor.noise_m + 0.02);  // above the floor's noise
  const double z1 = ceiling.found ? ceiling.height_m - 0.04 : std::numeric_limits<double>::infinity();
  // Slabs to leave out: each wall and each door gap, widened by the inlier distance.
  struct Slab {
    Line2 line;
    double half_m, a0, a1;
  };
  std::vector<Slab> slabs;
  const double m = s.wall_inlier_m + 0.02;
  for (const auto& w : walls) {
    Line2 l;
    l.point = w.from_m;
    l.direction = w.direction();
    l.normal = {-l.direction.y(), l.direction.x()};
    slabs.push_back({l, w.thickness_m / 2 + m, -w.thickness_m / 2 - m, w.length_m() + w.thickness_m / 2 + m});
  }
  for (const auto& d : doors) {
    Line2 l;
    l.point = d.center_m;
    l.direction = {std::cos(d.yaw_rad), std::sin(d.yaw_rad)};
    l.normal = {-l.direction.y(), l.direction.x()};
    slabs.push_back({l, d.wall_thickness_m / 2 + m, -d.width_m / 2 - m, d.width_m / 2 + m});
  }
  std::vector<Point3> rest;
  for (const auto& p : cloud.points) {
    if (p.z() < z0 || p.z() > z1) continue;
    const Eigen::Vector2d xy = p.head<2>().cast<double>();
    bool in_wall = false;
    for (const auto& sl : slabs) {
      const double a = sl.line.along(xy);
      if (a >= sl.a0 && a <= sl.a1 && std::abs(sl.line.offset(xy)) <= sl.half_m) {
        in_wall = true;
        break;
      }
    }
    if (!in_wall) rest.push_back({xy, p.z() - floor.height_m});
  }
  const std::vector<std::vector<Point3>> clusters = connected(rest, s.obstacle_cell_m, 5);
  std::vector<std::size_t> others;
  for (std::size_t k = 0; k < clusters.size(); ++k) {
    const auto& pts = clusters[k];
    if (static_cast<int>(pts.size()) < s.obstacle_min_points) continue;
    if (auto st = fit_stairs(pts, s)) {
      stairs.push_back(*st);
      continue;
    }
    others.push_back(k);
  }
  const auto shuts_a_door = [&](const Obstacle& b, const std::vector<Point3>& pts) {
    return std::any_of(doors.begin(), doors.end(), [&](const Door& d) { return shuts(b, pts, d, s); });
  };
  for (std::size_t k : others) {
    const auto& pts = clusters[k];
    // The far end of a landing seen from beyond it, apart from the flight
    // seen from below (its top is out of sight of a low scanner).
    bool landing = false;
    for (auto& st : stairs) {
      const Eigen::Vector2d d(std::cos(st.yaw_rad), std::sin(st.yaw_rad)), c(-d.y(), d.x());
      const double top_end = d.dot(st.start_m) + st.steps * st.tread_m;
      std::vector<double> z, along;
      bool fits = true;
      for (const auto& p : pts) {
        const double a = d.dot(p.xy - st.start_m) + d.dot(st.start_m), x = c.dot(p.xy - st.start_m);
        if (a < top_end - 0.05 || a > top_end + 3.0 || std::abs(x) > st.width_m / 2 + 0.1) {
          fits = false;
          break;
        }
        z.push_back(p.z);
        along.push_back(a);
      }
      if (!fits || std::abs(quantile(z, 0.99) - st.steps * st.riser_m) > 0.05) continue;
      st.landing_m = std::max(st.landing_m, quantile(along, 1.0) - top_end);
      st.points += static_cast<int>(pts.size());
      landing = true;
      break;
    }
    if (landing) continue;
    const auto keep = [&](const Obstacle& o) {
      if (o.size_m.z() >= s.obstacle_min_height_m) obstacles.push_back(o);
    };
    const Obstacle o = box_of(pts, floor.height_m);
    if (!oversize(o, s) && !shuts_a_door(o, pts)) {
      keep(o);
      continue;
    }
    // Too large for a thing: structure the wall finder missed (columns of
    // points over a wall's height) or several things touching. Or a box
    // across a doorway its points leave open: the wall's far face and
    // lintel beside it (just beyond the wall's slab) with what was seen
    // through it (freiburg1_360.bt). Without the tall columns, on a finer
    // grid, it falls apart into the things; what is still too large, or
    // still shuts a door, is dropped.
    for (const auto& part : connected(without_tall_columns(pts, s), s.obstacle_cell_m, 3)) {
      if (static_cast<int>(part.size()) < s.obstacle_min_points) continue;
      const Obstacle b = box_of(part, floor.height_m);
      if (oversize(b, s) || shuts_a_door(b, part))
        ++dropped;
      else
        keep(b);
    }
  }
}

}  // namespace rise::semantic::detail
