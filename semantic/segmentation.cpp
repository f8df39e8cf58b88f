#include "semantic/segmentation.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <iterator>
#include <cmath>
#include <stdexcept>
#include <string>

#include "semantic/segmentation_internal.hpp"

namespace rise::semantic {
namespace detail {

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(std::clamp(q, 0.0, 1.0) * static_cast<double>(v.size() - 1) + 0.5);
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

void check_grid(const Eigen::Vector2d& extent_m, double cell_m, const char* what) {
  const double cells = (extent_m.x() / cell_m + 1) * (extent_m.y() / cell_m + 1);
  if (!(cells <= 16e6))
    throw std::invalid_argument(std::string("segment: ") + what + " spans " + std::to_string(extent_m.x()) + " x " +
                                std::to_string(extent_m.y()) + " m: more than 16 million cells of " +
                                std::to_string(cell_m) + " m (crop the cloud or raise the cell size)");
}

namespace {

// Adds the scatter of xy about its own mean to C; returns the sum of xy.
Eigen::Vector2d add_scatter(const std::vector<Eigen::Vector2d>& xy, Eigen::Matrix2d& C) {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (const auto& p : xy) sum += p;
  const Eigen::Vector2d c = sum / static_cast<double>(xy.size());
  for (const auto& p : xy) C += (p - c) * (p - c).transpose();
  return sum;
}

// The line through `point` along the major axis of the scatter C.
Line2 major_axis_line(const Eigen::Matrix2d& C, const Eigen::Vector2d& point) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(C);
  Line2 l;
  l.point = point;
  l.direction = es.eigenvectors().col(1).normalized();
  l.normal = {-l.direction.y(), l.direction.x()};
  return l;
}

}  // namespace

Line2 fit_line(const std::vector<Eigen::Vector2d>& xy) {
  if (xy.empty()) return {};
  Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
  const Eigen::Vector2d sum = add_scatter(xy, C);
  return major_axis_line(C, sum / static_cast<double>(xy.size()));
}

Line2 fit_parallel_lines(const std::vector<std::vector<Eigen::Vector2d>>& lines) {
  Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  std::size_t n = 0;
  for (const auto& xy : lines)
    if (!xy.empty()) sum += add_scatter(xy, C), n += xy.size();
  return n == 0 ? Line2{} : major_axis_line(C, sum / static_cast<double>(n));
}

namespace {

// Least-squares plane z = a x + b y + c through the points within `band_m`
// of height z0 (then once more around the fitted plane). Returns a, b, c
// and the inlier count; points as (x, y, z).
struct HeightPlane {
  double a = 0, b = 0, c = 0;
  int inliers = 0;
  Eigen::Vector2d min_m{0, 0}, max_m{0, 0}, centre_m{0, 0};
  double at(const Eigen::Vector2d& xy) const { return a * xy.x() + b * xy.y() + c; }
};

HeightPlane fit_height_plane(const Cloud& cloud, double z0, double band_m) {
  HeightPlane plane;
  plane.c = z0;
  for (int pass = 0; pass < 2; ++pass) {
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    Eigen::Vector2d lo(1e30, 1e30), hi(-1e30, -1e30), sum(0, 0);
    int n = 0;
    for (const auto& pf : cloud.points) {
      const Eigen::Vector2d xy = pf.head<2>().cast<double>();
      if (std::abs(pf.z() - plane.at(xy)) > band_m) continue;
      const Eigen::Vector3d row(xy.x(), xy.y(), 1.0);
      A += row * row.transpose();
      rhs += row * pf.z();
      lo = lo.cwiseMin(xy);
      hi = hi.cwiseMax(xy);
      sum += xy;
      ++n;
    }
    if (n < 3) return plane;
    const Eigen::Vector3d x = A.ldlt().solve(rhs);
    if (!x.allFinite()) return plane;
    plane = {x[0], x[1], x[2], n, lo, hi, sum / n};
  }
  return plane;
}

// The xy area (m²) covered by the points within band_m of the plane, on a 10 cm grid.
double covered_area_m2(const Cloud& cloud, const HeightPlane& plane, double band_m) {
  std::vector<long long> keys;
  for (const auto& pf : cloud.points) {
    const Eigen::Vector2d xy = pf.head<2>().cast<double>();
    if (std::abs(pf.z() - plane.at(xy)) > band_m) continue;
    keys.push_back(static_cast<long long>(std::floor(xy.x() / 0.1)) * 1000003LL +
                   static_cast<long long>(std::floor(xy.y() / 0.1)));
  }
  std::sort(keys.begin(), keys.end());
  return 0.01 * static_cast<double>(std::unique(keys.begin(), keys.end()) - keys.begin());
}

}  // namespace

void find_floor_and_ceiling(const Cloud& cloud, const SegmentationSettings& s, Floor& floor, Ceiling& ceiling) {
  float zmin = std::numeric_limits<float>::infinity(), zmax = -zmin;
  for (const auto& p : cloud.points) {
    zmin = std::min(zmin, p.z());
    zmax = std::max(zmax, p.z());
  }
  if (!((zmax - zmin) / s.height_bin_m < 1e6))
    throw std::invalid_argument("segment: the cloud spans " + std::to_string(zmax - zmin) + " m in height: more than 10^6 bins of height_bin_m");
  const int bins = std::max(1, static_cast<int>(std::ceil((zmax - zmin) / s.height_bin_m)) + 1);
  std::vector<int> h(static_cast<std::size_t>(bins), 0);
  for (const auto& p : cloud.points)
    ++h[static_cast<std::size_t>(std::clamp(static_cast<int>((p.z() - zmin) / s.height_bin_m), 0, bins - 1))];
  // Horizontal surfaces are peaks of the height histogram over the even
  // spread of the vertical ones: smooth over the plane band, take the local
  // maxima that hold at least 2 % of the points.
  const int half = std::max(1, static_cast<int>(std::lround(s.plane_band_m / s.height_bin_m)));
  std::vector<int> sm(h.size(), 0);
  for (int i = 0; i < bins; ++i)
    for (int j = std::max(0, i - half); j <= std::min(bins - 1, i + half); ++j) sm[static_cast<std::size_t>(i)] += h[static_cast<std::size_t>(j)];
  const double min_count = 0.02 * static_cast<double>(cloud.size());
  std::vector<int> peaks;
  for (int i = 0; i < bins; ++i) {
    const int v = sm[static_cast<std::size_t>(i)];
    if (v < min_count) continue;
    bool top = true;
    for (int j = std::max(0, i - 2 * half); j <= std::min(bins - 1, i + 2 * half) && top; ++j)
      if (sm[static_cast<std::size_t>(j)] > v || (sm[static_cast<std::size_t>(j)] == v && j < i)) top = false;
    if (top) peaks.push_back(i);
  }
  const auto peak_z = [&](int i) { return zmin + (i + 0.5) * s.height_bin_m; };
  // The floor: the lowest peak that is a plane of at least 1 m².
  for (int i : peaks) {
    const HeightPlane p = fit_height_plane(cloud, peak_z(i), s.plane_band_m);
    if (p.inliers < min_count || covered_area_m2(cloud, p, s.plane_band_m) < 1.0) continue;
    floor.height_m = p.at(p.centre_m);
    floor.normal = Eigen::Vector3d(-p.a, -p.b, 1.0).normalized();
    floor.min_m = p.min_m;
    floor.max_m = p.max_m;
    floor.points = p.inliers;
    break;
  }
  if (floor.points == 0) throw std::invalid_argument("segment: no floor (no horizontal plane of 1 m² near the bottom)");
  // Its noise, from below: nothing else lies just under a floor.
  std::vector<double> under;
  for (const auto& p : cloud.points)
    if (p.z() < floor.height_m && p.z() > floor.height_m - 0.3) under.push_back(floor.height_m - p.z());
  floor.noise_m = quantile(under, 0.98);
  // The ceiling: the highest such peak well above the floor.
  for (auto it = peaks.rbegin(); it != peaks.rend(); ++it) {
    if (peak_z(*it) < floor.height_m + s.min_ceiling_clearance_m) break;
    const HeightPlane p = fit_height_plane(cloud, peak_z(*it), s.plane_band_m);
    if (p.inliers < min_count || covered_area_m2(cloud, p, s.plane_band_m) < 1.0) continue;
    ceiling.found = true;
    ceiling.height_m = p.at(p.centre_m);
    ceiling.normal = Eigen::Vector3d(p.a, p.b, -1.0).normalized();
    ceiling.min_m = p.min_m;
    ceiling.max_m = p.max_m;
    ceiling.points = p.inliers;
    break;
  }
}

}  // namespace detail

Segmentation segment(const Cloud& cloud, const SegmentationSettings& settings) {
  if (cloud.empty()) throw std::invalid_argument("segment: empty cloud");
  // Points with NaN or infinite coordinates (an organised cloud's holes) are left out.
  const auto finite = [](const Eigen::Vector3f& p) { return p.allFinite(); };
  Cloud kept;
  const bool all_finite = std::all_of(cloud.points.begin(), cloud.points.end(), finite);
  if (!all_finite) {
    std::copy_if(cloud.points.begin(), cloud.points.end(), std::back_inserter(kept.points), finite);
    if (kept.empty()) throw std::invalid_argument("segment: no finite point");
  }
  const Cloud& c = all_finite ? cloud : kept;
  Segmentation out;
  detail::find_floor_and_ceiling(c, settings, out.floor, out.ceiling);
  detail::find_walls_and_doors(c, settings, out.floor, out.ceiling, out.walls, out.doors);
  detail::find_stairs_and_obstacles(c, settings, out.floor, out.ceiling, out.walls, out.doors, out.stairs,
                                    out.obstacles, out.oversize_clusters_dropped);
  return out;
}

Eigen::Matrix3d levelling_rotation(const Cloud& cloud, const SegmentationSettings& settings) {
  if (cloud.empty()) throw std::invalid_argument("levelling_rotation: empty cloud");
  Cloud c;
  std::copy_if(cloud.points.begin(), cloud.points.end(), std::back_inserter(c.points),
               [](const Eigen::Vector3f& p) { return p.allFinite(); });
  // The floor of the height histogram, plane-fitted, turned onto +z; twice,
  // as a tilted floor is a broad peak.
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  for (int pass = 0; pass < 2; ++pass) {
    Floor floor;
    Ceiling ceiling;
    detail::find_floor_and_ceiling(c, settings, floor, ceiling);
    const Eigen::Matrix3d step = Eigen::Quaterniond::FromTwoVectors(floor.normal, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    R = step * R;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = step;
    c = transformed(c, T);
  }
  return R;
}

}  // namespace rise::semantic
