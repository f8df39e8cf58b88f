#include "semantic/floor_plan.hpp"

#include "semantic/segmentation_internal.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <tuple>
#include <utility>

namespace rise::semantic {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A length in cells of `res` (at least one).
int cell_count(double m, double res) { return std::max(1, static_cast<int>(std::lround(m / res))); }

// The grid as 0/255 masks, image row = grid row.
struct Masks {
  cv::Mat occupied, free, unknown;
};

Masks masks_of(const OccupancyGrid& g) {
  Masks m{cv::Mat::zeros(g.height, g.width, CV_8U), cv::Mat::zeros(g.height, g.width, CV_8U),
          cv::Mat::zeros(g.height, g.width, CV_8U)};
  for (int r = 0; r < g.height; ++r)
    for (int c = 0; c < g.width; ++c) {
      const CellState s = g.at(c, r);
      (s == CellState::Occupied ? m.occupied : s == CellState::Free ? m.free : m.unknown).at<uint8_t>(r, c) = 255;
    }
  return m;
}

// The building's wall directions in [0, pi), each with its share of the
// strongest: peaks of the histogram (1° bins) of the occupancy's local
// orientation, each at least minor_direction_share of the strongest. The orientation is the structure
// tensor's (gradient products averaged over a few cells), weighted by its
// anisotropy: a single cell's gradient snaps to the grid's axes and
// diagonals on a staircase-aliased line, the averaged tensor does not.
std::vector<std::pair<double, double>> wall_directions(const cv::Mat& occupied, const FloorPlanSettings& s) {
  cv::Mat f, gx, gy;
  occupied.convertTo(f, CV_32F, 1.0 / 255.0);
  cv::GaussianBlur(f, f, cv::Size(0, 0), 1.0);
  cv::Sobel(f, gx, CV_32F, 1, 0, 3);
  cv::Sobel(f, gy, CV_32F, 0, 1, 3);
  cv::Mat jxx = gx.mul(gx), jxy = gx.mul(gy), jyy = gy.mul(gy);
  for (cv::Mat* j : {&jxx, &jxy, &jyy}) cv::GaussianBlur(*j, *j, cv::Size(0, 0), 3.0);
  constexpr int kBins = 180;
  std::vector<double> hist(kBins, 0.0);
  for (int r = 0; r < f.rows; ++r)
    for (int c = 0; c < f.cols; ++c) {
      const double xx = jxx.at<float>(r, c), xy = jxy.at<float>(r, c), yy = jyy.at<float>(r, c);
      const double anisotropy = std::hypot(xx - yy, 2 * xy);
      if (anisotropy < 1e-3) continue;
      // The dominant gradient's angle; the wall runs across it.
      double a = 0.5 * std::atan2(2 * xy, xx - yy) + kPi / 2;
      a = std::fmod(a + 2 * kPi, kPi);
      hist[static_cast<std::size_t>(static_cast<int>(a / kPi * kBins) % kBins)] += anisotropy;
    }
  const auto wrap = [](int i) { return static_cast<std::size_t>(((i % kBins) + kBins) % kBins); };
  std::vector<double> smooth(kBins, 0.0);
  for (int i = 0; i < kBins; ++i)
    for (int k = -2; k <= 2; ++k) smooth[wrap(i)] += hist[wrap(i + k)];
  // Peaks: the largest bin within the angle tolerance either side, and
  // within twice it but for a higher bin beyond a valley below half its
  // height (a hall's two walls 10 degrees apart are two directions; a
  // direction's bumpy flank is not one).
  const int near = std::max(2, static_cast<int>(std::lround(s.angle_tolerance_rad / kPi * kBins)));
  std::vector<std::pair<double, int>> peaks;
  for (int i = 0; i < kBins; ++i) {
    const double h = smooth[wrap(i)];
    bool top = h > 0.0;
    for (const int dir : {-1, 1}) {
      double valley = h;
      for (int k = 1; k <= 2 * near && top; ++k) {
        const double v = smooth[wrap(i + dir * k)];
        const bool higher = dir < 0 ? v >= h : v > h;
        if (higher) top = k > near && valley <= h / 2;
        valley = std::min(valley, v);
      }
    }
    if (top) peaks.emplace_back(smooth[wrap(i)], i);
  }
  std::sort(peaks.rbegin(), peaks.rend());
  std::vector<std::pair<double, double>> out;
  for (const auto& [weight, bin] : peaks) {
    if (weight < s.minor_direction_share * peaks.front().first) break;
    // Sub-bin refinement: the weighted mean angle of the raw bins around the peak.
    double sum = 0.0, w = 0.0;
    for (int k = -3; k <= 3; ++k) {
      sum += hist[wrap(bin + k)] * (bin + k + 0.5);
      w += hist[wrap(bin + k)];
    }
    out.emplace_back(std::fmod((sum / w) / kBins * kPi + kPi, kPi), weight / peaks.front().first);
  }
  return out;
}

// The grid turned so that direction `theta` runs along the image rows:
// pixel (u, v) is along u, across v, its centre at along a0 + res (u + ½).
struct Frame {
  Eigen::Vector2d d, n;
  double a0 = 0, o0 = 0, res = 0;
  cv::Mat occupied, free;  // 0/255, outside the grid: neither

  Eigen::Vector2d world(double along_m, double offset_m) const { return along_m * d + offset_m * n; }
  double along_of_col(double col) const { return a0 + res * col; }  // left edge of column `col`
  double offset_of_row(double row) const { return o0 + res * row; }
};

Frame turned(const OccupancyGrid& g, const Masks& m, double theta) {
  Frame f;
  f.res = g.resolution_m;
  f.d = {std::cos(theta), std::sin(theta)};
  f.n = {-f.d.y(), f.d.x()};
  double a_lo = 1e300, a_hi = -1e300, o_lo = 1e300, o_hi = -1e300;
  for (const double x : {0.0, g.width * f.res})
    for (const double y : {0.0, g.height * f.res}) {
      const Eigen::Vector2d p = g.origin_m + Eigen::Vector2d(x, y);
      a_lo = std::min(a_lo, f.d.dot(p)), a_hi = std::max(a_hi, f.d.dot(p));
      o_lo = std::min(o_lo, f.n.dot(p)), o_hi = std::max(o_hi, f.n.dot(p));
    }
  f.a0 = a_lo - f.res;
  f.o0 = o_lo - f.res;
  const int cols = static_cast<int>(std::ceil((a_hi - a_lo) / f.res)) + 3;
  const int rows = static_cast<int>(std::ceil((o_hi - o_lo) / f.res)) + 3;
  // Grid pixel (x, y) has its centre at origin + res (x + ½, y + ½).
  const Eigen::Vector2d c0 = g.origin_m + Eigen::Vector2d(0.5, 0.5) * f.res;
  const cv::Matx23d M(f.d.x(), f.d.y(), (f.d.dot(c0) - f.a0) / f.res - 0.5,  //
                      f.n.x(), f.n.y(), (f.n.dot(c0) - f.o0) / f.res - 0.5);
  cv::warpAffine(m.occupied, f.occupied, M, cv::Size(cols, rows), cv::INTER_NEAREST, cv::BORDER_CONSTANT, 0);
  cv::warpAffine(m.free, f.free, M, cv::Size(cols, rows), cv::INTER_NEAREST, cv::BORDER_CONSTANT, 0);
  return f;
}

// A wall face in a turned frame: a connected strip of long occupied runs.
struct Face {
  int r0 = 0, r1 = 0;  // the rows its occupied cells fill (inclusive)
  int c0 = 0, c1 = 0;  // the columns it spans (inclusive)
  std::vector<cv::Point> cells;  // its occupied cells (x = column, y = row)
  double mid() const { return (r0 + r1) / 2.0; }
};

std::vector<Face> faces_of(const Frame& f, const FloorPlanSettings& s) {
  const auto cells = [&](double m) { return cell_count(m, f.res); };
  // Rows wobble by a cell on a real map: a face may step between neighbouring rows.
  cv::Mat strips;
  cv::dilate(f.occupied, strips, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(1, 3)));
  cv::morphologyEx(strips, strips, cv::MORPH_CLOSE,
                   cv::getStructuringElement(cv::MORPH_RECT, cv::Size(cells(s.noise_gap_m) + 1, 1)));
  cv::morphologyEx(strips, strips, cv::MORPH_OPEN,
                   cv::getStructuringElement(cv::MORPH_RECT, cv::Size(cells(s.min_face_length_m), 1)));
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(strips, labels, stats, centroids, 8, CV_32S);
  std::vector<Face> out;
  for (int i = 1; i < n; ++i) {
    const int x = stats.at<int>(i, cv::CC_STAT_LEFT), y = stats.at<int>(i, cv::CC_STAT_TOP);
    const int w = stats.at<int>(i, cv::CC_STAT_WIDTH), h = stats.at<int>(i, cv::CC_STAT_HEIGHT);
    std::vector<int> per_row(static_cast<std::size_t>(h), 0);
    Face face;
    face.c0 = x + w, face.c1 = x;
    for (int r = y; r < y + h; ++r)
      for (int c = x; c < x + w; ++c)
        if (labels.at<int>(r, c) == i && f.occupied.at<uint8_t>(r, c) != 0) {
          ++per_row[static_cast<std::size_t>(r - y)];
          face.cells.emplace_back(c, r);
          face.c0 = std::min(face.c0, c), face.c1 = std::max(face.c1, c);
        }
    if (face.cells.empty()) continue;
    // The face's rows: those with a fair share of its cells (not a stray cell's).
    const int most = *std::max_element(per_row.begin(), per_row.end());
    face.r0 = -1;
    for (int k = 0; k < h; ++k)
      if (per_row[static_cast<std::size_t>(k)] * 10 >= most * 3) {
        if (face.r0 < 0) face.r0 = y + k;
        face.r1 = y + k;
      }
    out.push_back(std::move(face));
  }
  return out;
}

int find_root(std::vector<int>& parent, int i) {
  while (parent[static_cast<std::size_t>(i)] != i) i = parent[static_cast<std::size_t>(i)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
  return i;
}

// Share of free cells in rows r0..r1, columns c0..c1 of the frame.
double free_share(const Frame& f, int r0, int r1, int c0, int c1) {
  r0 = std::max(r0, 0), c0 = std::max(c0, 0);
  r1 = std::min(r1, f.free.rows - 1), c1 = std::min(c1, f.free.cols - 1);
  if (r1 < r0 || c1 < c0) return 0.0;
  const cv::Mat roi = f.free(cv::Range(r0, r1 + 1), cv::Range(c0, c1 + 1));
  return cv::countNonZero(roi) / static_cast<double>(roi.total());
}

// A straight wall before its ends meet the others: along a0..a1 of a line
// `offset` across direction d.
struct Piece {
  Eigen::Vector2d d, n;
  double offset = 0, a0 = 0, a1 = 0, thickness = 0;
  bool both_faces = false;
  int cells = 0;
  bool joined = false;  // an end meets another wall, or another lies on its line
  std::vector<std::pair<double, double>> doorways;  // along, a0 < from < to < a1
};

// The state of the cell holding point x; Unknown outside the grid.
CellState state_at(const OccupancyGrid& grid, const Eigen::Vector2d& x) {
  const Eigen::Vector2i c = grid.cell_of(x);
  return grid.contains(c.x(), c.y()) ? grid.at(c.x(), c.y()) : CellState::Unknown;
}

// Share of free cells of `grid` over the rectangle along a0..a1, offset
// o0..o1 of the line (d, n), sampled at the grid's resolution.
double free_share(const OccupancyGrid& grid, const Eigen::Vector2d& d, const Eigen::Vector2d& n, double a0,
                  double a1, double o0, double o1) {
  int free = 0, all = 0;
  for (double a = a0; a <= a1; a += grid.resolution_m)
    for (double o = o0; o <= o1; o += grid.resolution_m) {
      ++all;
      if (state_at(grid, a * d + o * n) == CellState::Free) ++free;
    }
  return all == 0 ? 0.0 : free / static_cast<double>(all);
}

// Whether the cross-section through wall p at along `a` (its thickness
// and a cell either side) holds an occupied cell.
bool solid_across(const OccupancyGrid& grid, const Piece& p, double a) {
  const double t = p.thickness / 2 + grid.resolution_m;
  for (double o = -t; o <= t; o += grid.resolution_m) {
    if (state_at(grid, a * p.d + (p.offset + o) * p.n) == CellState::Occupied) return true;
  }
  return false;
}

// Share of the cells along a0..a1 of wall p's line whose cross-section is solid.
double solid_share(const OccupancyGrid& grid, const Piece& p, double a0, double a1) {
  int solid = 0, all = 0;
  for (double a = a0; a <= a1; a += grid.resolution_m, ++all) solid += solid_across(grid, p, a) ? 1 : 0;
  return all == 0 ? 0.0 : solid / static_cast<double>(all);
}

// The clear width of the gap around along `mid` of wall p's line on the
// grid itself: from mid out to the first solid cross-section either side.
// The faces' cells come from a turned copy of the grid, which can move a
// gap's ends by a cell.
double clear_width(const OccupancyGrid& grid, const Piece& p, double mid, double limit) {
  const double step = grid.resolution_m / 2;
  double lo = mid, hi = mid;
  while (mid - lo < limit && !solid_across(grid, p, lo - step)) lo -= step;
  while (hi - mid < limit && !solid_across(grid, p, hi + step)) hi += step;
  return hi - lo;
}

// How far from wall p's face, to `side` (+1 along p.n, -1 against), free
// cells reach through the gap a0..a1: the farthest free cell on a line
// across it before an occupied one, over the lines.
double free_reach(const OccupancyGrid& grid, const Piece& p, double a0, double a1, int side, double limit) {
  const double res = grid.resolution_m, face = p.thickness / 2;
  double reach = 0.0;
  for (double a = a0; a <= a1; a += res)
    for (double o = res; o <= limit; o += res) {
      // Outside the grid counts as unknown: a line that leaves it does not come back.
      const CellState state = state_at(grid, a * p.d + (p.offset + side * (face + o)) * p.n);
      if (state == CellState::Occupied) break;
      if (state == CellState::Free) reach = std::max(reach, o);
    }
  return reach;
}

// A doorway along g0..g1 of wall `p`'s line: at least a door's clear
// width on the grid itself; free cells in the gap's middle, and on both
// sides of the wall in front of it, reaching door_min_depth_m beyond it
// (a doorway leads somewhere, a shallow recess does not); solid wall (not
// a dotted line of cells a laser grazed) for door_jamb_m before g0 and
// after g1, where the gap's ends are p's (`jamb_before`, `jamb_after`).
bool doorway(const OccupancyGrid& grid, const Piece& p, double g0, double g1, const FloorPlanSettings& s,
             bool jamb_before = true, bool jamb_after = true, bool beside_corner = false) {
  const double m0 = g0 + (g1 - g0) / 5, m1 = g1 - (g1 - g0) / 5, t = p.thickness / 2, res = grid.resolution_m;
  const double depth = beside_corner ? s.corner_door_min_depth_m : s.door_min_depth_m;
  if (clear_width(grid, p, (g0 + g1) / 2, s.door_min_width_m) < s.door_min_width_m - res / 2) return false;
  if (free_reach(grid, p, m0, m1, -1, depth) < depth - res || free_reach(grid, p, m0, m1, +1, depth) < depth - res)
    return false;
  if (jamb_before && solid_share(grid, p, g0 - s.door_jamb_m, g0 - res / 2) < s.door_jamb_solid) return false;
  if (jamb_after && solid_share(grid, p, g1 + res / 2, g1 + s.door_jamb_m) < s.door_jamb_solid) return false;
  return free_share(grid, p.d, p.n, m0, m1, p.offset - t, p.offset + t) >= s.door_min_free &&
         free_share(grid, p.d, p.n, m0, m1, p.offset - t - s.door_clearance_m, p.offset - t - res) >= s.door_min_free &&
         free_share(grid, p.d, p.n, m0, m1, p.offset + t + res, p.offset + t + s.door_clearance_m) >= s.door_min_free;
}

// One wall line from the occupied cells of its faces (world xy): its centre
// line fitted through them, its thickness their spread across it, split at
// gaps along it that are neither narrower than a door nor a doorway (free
// space in the gap's middle and on both sides of it). False, adding nothing,
// when the cells spread wider than a wall's thickness across the line
// (unless they are a single face and `refuse_thick` is false: a face is
// straight by construction).
bool split_wall(const OccupancyGrid& grid, const std::vector<Eigen::Vector2d>& xy, bool both_faces, bool single_face,
                const FloorPlanSettings& s, std::vector<Piece>& out, bool refuse_thick = false,
                const std::optional<detail::Line2>& fitted = std::nullopt) {
  const detail::Line2 line = fitted ? *fitted : detail::fit_line(xy);
  std::vector<double> along, across;
  for (const auto& p : xy) along.push_back(line.along(p)), across.push_back(line.offset(p));
  const double lo = detail::quantile(across, 0.03), hi = detail::quantile(across, 0.97);
  Piece proto;
  proto.d = line.direction, proto.n = line.normal;
  proto.offset = line.normal.dot(line.point) + (lo + hi) / 2;
  proto.thickness = std::max(s.min_wall_thickness_m, hi - lo + grid.resolution_m);
  const auto [shortest, longest] = std::minmax_element(along.begin(), along.end());
  if (proto.thickness > s.max_wall_thickness_m && refuse_thick) return false;
  if (proto.thickness > s.max_wall_thickness_m && (!single_face || *longest - *shortest >= 2 * s.min_wall_length_m)) {
    if (!single_face) return false;
    // A curved face (a drifting map's long wall): two straighter halves.
    const double mid = detail::quantile(along, 0.5);
    std::vector<Eigen::Vector2d> lo_half, hi_half;
    for (std::size_t k = 0; k < xy.size(); ++k) (along[k] < mid ? lo_half : hi_half).push_back(xy[k]);
    split_wall(grid, lo_half, false, true, s, out);
    split_wall(grid, hi_half, false, true, s, out);
    return true;
  }
  proto.both_faces = both_faces;
  proto.cells = static_cast<int>(xy.size());
  const double base = line.direction.dot(line.point), res = grid.resolution_m;
  std::sort(along.begin(), along.end());
  Piece cur = proto;
  cur.a0 = base + along.front() - res / 2;
  for (std::size_t k = 1; k <= along.size(); ++k) {
    const double prev = base + along[k - 1] + res / 2;
    if (k < along.size()) {
      const double next = base + along[k] - res / 2, gap = next - prev;
      if (gap < s.door_min_width_m) continue;
      if (gap <= s.door_max_width_m + 2 * res) {
        if (doorway(grid, proto, prev, next, s)) {
          cur.doorways.emplace_back(prev, next);
          continue;
        }
      }
    }
    cur.a1 = prev;
    if (cur.a1 - cur.a0 >= s.min_wall_length_m) out.push_back(cur);
    if (k < along.size()) {
      cur = proto;
      cur.a0 = base + along[k] - res / 2;
    }
  }
  return true;
}

// The walls of one direction: faces joined into walls (the two faces of
// one wall; collinear faces across door-wide gaps).
void walls_of(const OccupancyGrid& grid, const Frame& f, const FloorPlanSettings& s, std::vector<Piece>& out) {
  std::vector<Face> faces = faces_of(f, s);
  const auto collinear = [&](double mid_a, double mid_b) { return std::abs(mid_a - mid_b) * f.res <= s.collinear_offset_m; };
  std::vector<int> parent(faces.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (std::size_t i = 0; i < faces.size(); ++i)
    for (std::size_t j = i + 1; j < faces.size(); ++j) {
      const Face &a = faces[i], &b = faces[j];
      const int overlap = std::min(a.c1, b.c1) - std::max(a.c0, b.c0) + 1;
      const int gap = -overlap;  // columns between them when they do not overlap
      bool join = false;
      if (collinear(a.mid(), b.mid()) && gap * f.res <= s.door_max_width_m) {
        join = true;
      } else if ((std::max(a.r1, b.r1) - std::min(a.r0, b.r0) + 1) * f.res <= s.max_wall_thickness_m &&
                 overlap * 2 >= std::min(a.c1 - a.c0, b.c1 - b.c0)) {
        // Two faces of one wall have no free space between them.
        const Face &lo = a.mid() < b.mid() ? a : b, &hi = a.mid() < b.mid() ? b : a;
        join = free_share(f, lo.r1 + 1, hi.r0 - 1, std::max(a.c0, b.c0), std::min(a.c1, b.c1)) < 0.05;
      }
      if (join) parent[static_cast<std::size_t>(find_root(parent, static_cast<int>(i)))] = find_root(parent, static_cast<int>(j));
    }
  std::vector<std::vector<int>> groups(faces.size());
  for (std::size_t i = 0; i < faces.size(); ++i)
    groups[static_cast<std::size_t>(find_root(parent, static_cast<int>(i)))].push_back(static_cast<int>(i));
  const auto cells_of = [&](const Face& face, std::vector<Eigen::Vector2d>& xy, bool own_rows = false) {
    for (const auto& c : face.cells)
      if (!own_rows || (c.y >= face.r0 && c.y <= face.r1))
        xy.push_back(f.world(f.along_of_col(c.x + 0.5), f.offset_of_row(c.y + 0.5)));
  };
  // A face alone. One spread wider than a wall is clutter, a wall with
  // clutter standing against it, or a curved wall. Shorter than two
  // walls' minimum: clutter, no wall. Else the cells of its own rows
  // (those with a fair share of its cells), where they are a straight
  // line (straight_share of them near their fitted line) whose pieces keep
  // trim_keep of the face's length: the wall, without the clutter. Else
  // two straighter halves (split_wall).
  const auto alone = [&](const Face& face) {
    std::vector<Eigen::Vector2d> xy;
    cells_of(face, xy);
    if (split_wall(grid, xy, false, true, s, out, true)) return;
    const double length = (face.c1 - face.c0 + 1) * f.res;
    if (length < 2 * s.min_wall_length_m) return;
    std::vector<Eigen::Vector2d> own;
    cells_of(face, own, true);
    const detail::Line2 line = detail::fit_line(own);
    const auto near = std::count_if(own.begin(), own.end(), [&](const Eigen::Vector2d& q) {
      return std::abs(line.offset(q)) <= s.straight_within_m;
    });
    if (static_cast<double>(near) >= s.straight_share * static_cast<double>(own.size())) {
      std::vector<Piece> trimmed;
      split_wall(grid, own, false, true, s, trimmed);
      double kept = 0.0;
      for (const Piece& p : trimmed) kept += p.a1 - p.a0;
      if (kept >= s.trim_keep * length) {
        out.insert(out.end(), trimmed.begin(), trimmed.end());
        return;
      }
    }
    split_wall(grid, xy, false, true, s, out);
  };
  // A group's faces in more than one line (two faces of a wall) as
  // parallel lines, one offset for each line of collinear faces: one line
  // through all their cells tilts towards the shorter face (a cabinet's
  // top beside a 5 m wall: 2 degrees). Faces all in one line: none (the
  // plain fit is the same).
  const auto parallel_lines = [&](const std::vector<int>& group) -> std::optional<detail::Line2> {
    std::vector<std::vector<Eigen::Vector2d>> lines;
    std::vector<std::size_t> line_of;  // each face's line: that of the first face before it collinear with it
    for (std::size_t i = 0; i < group.size(); ++i) {
      const Face& face = faces[static_cast<std::size_t>(group[i])];
      std::size_t j = 0;
      while (j < i && !collinear(face.mid(), faces[static_cast<std::size_t>(group[j])].mid())) ++j;
      line_of.push_back(j < i ? line_of[j] : lines.size());
      if (j == i) lines.emplace_back();
      cells_of(face, lines[line_of.back()]);
    }
    if (lines.size() < 2) return std::nullopt;
    return detail::fit_parallel_lines(lines);
  };
  for (const auto& group : groups) {
    if (group.empty()) continue;
    if (group.size() == 1) {
      alone(faces[static_cast<std::size_t>(group.front())]);
      continue;
    }
    std::vector<Eigen::Vector2d> xy;
    bool both = false;
    for (const int i : group) {
      const Face& face = faces[static_cast<std::size_t>(i)];
      cells_of(face, xy);
      for (const int j : group) both = both || face.r1 < faces[static_cast<std::size_t>(j)].r0;
    }
    if (split_wall(grid, xy, both, false, s, out, false, parallel_lines(group))) continue;
    // Joined faces that do not make one straight slab: each on its own.
    for (const int i : group) alone(faces[static_cast<std::size_t>(i)]);
  }
}

// The occupied cells within half_m of `line`, along a0..a1 of it.
std::vector<cv::Point> cells_near(const OccupancyGrid& grid, const cv::Mat& occupied, const detail::Line2& line,
                                  double a0, double a1, double half_m) {
  const Eigen::Vector2d e0 = line.point + a0 * line.direction, e1 = line.point + a1 * line.direction;
  const Eigen::Vector2i lo = grid.cell_of(e0.cwiseMin(e1) - Eigen::Vector2d::Constant(half_m));
  const Eigen::Vector2i hi = grid.cell_of(e0.cwiseMax(e1) + Eigen::Vector2d::Constant(half_m));
  std::vector<cv::Point> out;
  for (int r = std::max(lo.y(), 0); r <= std::min(hi.y(), occupied.rows - 1); ++r)
    for (int c = std::max(lo.x(), 0); c <= std::min(hi.x(), occupied.cols - 1); ++c) {
      if (occupied.at<uint8_t>(r, c) == 0) continue;
      const Eigen::Vector2d q = grid.center(c, r);
      const double a = line.along(q);
      if (std::abs(line.offset(q)) <= half_m && a >= a0 && a <= a1) out.emplace_back(c, r);
    }
  return out;
}

// The longest stretch of `along` (sorted, not empty) with no gap of gap_m or more between neighbouring values: its
// first and last values.
std::pair<double, double> longest_run(const std::vector<double>& along, double gap_m) {
  if (along.empty()) throw std::invalid_argument("longest_run: no values");
  std::size_t best0 = 0, best1 = 0;
  for (std::size_t k0 = 0, k = 1; k <= along.size(); ++k)
    if (k == along.size() || along[k] - along[k - 1] >= gap_m) {
      if (along[k - 1] - along[k0] > along[best1] - along[best0]) best0 = k0, best1 = k - 1;
      k0 = k;
    }
  return {along[best0], along[best1]};
}

// Whether direction d lies more than twice the angle tolerance off every one of `thetas`.
bool off_directions(const Eigen::Vector2d& d, const std::vector<double>& thetas, const FloorPlanSettings& s) {
  const double a = std::atan2(d.y(), d.x());
  return std::all_of(thetas.begin(), thetas.end(),
                     [&](double t) { return std::abs(std::remainder(a - t, kPi)) > 2 * s.angle_tolerance_rad; });
}

// The slanted wall along `line` (a0..a1 of it), or false: three times, the
// line refitted to the cells within slant_within_m of it over a0..a1
// widened by a door's width at each end, a0..a1 then the longest stretch of
// them with no gap a door wide (so the stretch may grow by up to three door
// widths each way along cells in line with it); a wall where that stretch
// is minor_wall_min_length_m long, still off every direction, solid along
// slant_min_solid of it (a line drawn across clutter or across two walls is
// not) and with free space on one side at least. Its thickness is that of
// its cells within slant_within_m of the line, so at most 2 slant_within_m
// and a cell: the band, not max_wall_thickness_m, bounds it with the
// defaults (0.35 m against 0.5 m; the check is for a wider band).
bool slanted_wall(const OccupancyGrid& grid, const cv::Mat& occupied, detail::Line2 line, double a0, double a1,
                  const std::vector<double>& thetas, const FloorPlanSettings& s, Piece& out,
                  std::vector<cv::Point>& cells) {
  const double res = grid.resolution_m;
  std::vector<double> along;
  for (int pass = 0; pass < 3; ++pass) {
    cells = cells_near(grid, occupied, line, a0 - s.door_min_width_m, a1 + s.door_min_width_m, s.slant_within_m);
    if (cells.size() < 2) return false;
    std::vector<Eigen::Vector2d> xy;
    for (const cv::Point& c : cells) xy.push_back(grid.center(c.x, c.y));
    line = detail::fit_line(xy);
    along.clear();
    for (const auto& q : xy) along.push_back(line.along(q));
    std::sort(along.begin(), along.end());
    std::tie(a0, a1) = longest_run(along, s.door_min_width_m);
  }
  if (a1 - a0 < s.minor_wall_min_length_m || !off_directions(line.direction, thetas, s)) return false;
  cells = cells_near(grid, occupied, line, a0 - res / 2, a1 + res / 2, s.slant_within_m);
  std::vector<double> across;
  std::vector<char> seen(static_cast<std::size_t>((a1 - a0) / res) + 1, 0);
  for (const cv::Point& c : cells) {
    const Eigen::Vector2d q = grid.center(c.x, c.y);
    across.push_back(line.offset(q));
    seen[std::min(seen.size() - 1, static_cast<std::size_t>(std::max(0.0, (line.along(q) - a0) / res)))] = 1;
  }
  const double solid = static_cast<double>(std::count(seen.begin(), seen.end(), 1)) / static_cast<double>(seen.size());
  const double lo = detail::quantile(across, 0.03), hi = detail::quantile(across, 0.97);
  Piece p;
  p.d = line.direction, p.n = line.normal;
  p.offset = line.normal.dot(line.point) + (lo + hi) / 2;
  p.thickness = std::max(s.min_wall_thickness_m, hi - lo + res);
  const double base = line.direction.dot(line.point), t = p.thickness / 2;
  p.a0 = base + a0 - res / 2, p.a1 = base + a1 + res / 2;
  p.cells = static_cast<int>(cells.size());
  if (p.thickness > s.max_wall_thickness_m || solid < s.slant_min_solid) return false;
  if (std::max(free_share(grid, p.d, p.n, p.a0, p.a1, p.offset - t - s.door_clearance_m, p.offset - t - res),
               free_share(grid, p.d, p.n, p.a0, p.a1, p.offset + t + res, p.offset + t + s.door_clearance_m)) <
      s.door_min_free)
    return false;
  out = p;
  return true;
}

// Walls in no direction of their own. A building's one slanted wall holds
// too few of the occupancy's edges to make a peak of their histogram
// (PWR's 3.9 m, 16° off its main walls, lies on the main peak's flank),
// and a direction's frame sees it as a staircase of short faces, each
// found as a wall of the frame's direction. Candidates: the straight lines
// of occupied cells (probabilistic Hough on the cells grown by one, as a
// face's rows wobble by a cell), minor_wall_min_length_m long across gaps
// narrower than a door, off every found direction by over twice the angle
// tolerance; each one checked by slanted_wall. The cells of each wall
// found are set in `taken`, for the frames to leave out.
void slanted_walls(const OccupancyGrid& grid, const cv::Mat& occupied, const std::vector<double>& thetas,
                   const FloorPlanSettings& s, std::vector<Piece>& out, cv::Mat& taken) {
  const auto cells = [&](double m) { return cell_count(m, grid.resolution_m); };
  cv::Mat grown;
  cv::dilate(occupied, grown, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3)));
  std::vector<cv::Vec4i> segs;
  cv::HoughLinesP(grown, segs, 1, kPi / 360, std::max(1, cells(s.minor_wall_min_length_m) / 2),
                  cells(s.minor_wall_min_length_m), cells(s.door_min_width_m));
  const auto length = [](const cv::Vec4i& v) { return std::hypot(v[2] - v[0], v[3] - v[1]); };
  std::sort(segs.begin(), segs.end(), [&](const cv::Vec4i& a, const cv::Vec4i& b) { return length(a) > length(b); });
  taken = cv::Mat::zeros(occupied.size(), CV_8U);
  cv::Mat left = occupied.clone();
  for (const cv::Vec4i& seg : segs) {
    detail::Line2 line;
    line.point = grid.center(seg[0], seg[1]);
    line.direction = (grid.center(seg[2], seg[3]) - line.point).normalized();
    line.normal = {-line.direction.y(), line.direction.x()};
    if (!off_directions(line.direction, thetas, s)) continue;
    Piece p;
    std::vector<cv::Point> wall_cells;
    if (!slanted_wall(grid, left, line, 0.0, line.along(grid.center(seg[2], seg[3])), thetas, s, p, wall_cells))
      continue;
    for (const cv::Point& c : wall_cells) left.at<uint8_t>(c) = 0, taken.at<uint8_t>(c) = 255;
    out.push_back(p);
  }
}

// Frame f without the slanted walls' cells (`taken`, turned as f is),
// but for those on a run of a row a wall long (occupied cells closed across
// noise gaps) that holds a face's length of cells not taken, anywhere on
// it: a straight wall of f's direction that a slanted one meets or crosses
// keeps its cells (a slanted wall's own rows are its staircase).
void without_slanted(Frame& f, const Frame& taken, const FloorPlanSettings& s) {
  const auto cells = [&](double m) { return cell_count(m, f.res); };
  cv::Mat runs;
  cv::morphologyEx(f.occupied, runs, cv::MORPH_CLOSE,
                   cv::getStructuringElement(cv::MORPH_RECT, cv::Size(cells(s.noise_gap_m) + 1, 1)));
  cv::morphologyEx(runs, runs, cv::MORPH_OPEN,
                   cv::getStructuringElement(cv::MORPH_RECT, cv::Size(cells(s.min_wall_length_m), 1)));
  for (int r = 0; r < f.occupied.rows; ++r) {
    const uint8_t *run = runs.ptr<uint8_t>(r), *mine = taken.occupied.ptr<uint8_t>(r);
    uint8_t* occ = f.occupied.ptr<uint8_t>(r);
    for (int c0 = 0; c0 < f.occupied.cols;) {
      int c1 = c0;
      while (c1 < f.occupied.cols && (run[c1] != 0) == (run[c0] != 0)) ++c1;
      int own = 0;
      if (run[c0] != 0)
        for (int c = c0; c < c1; ++c) own += occ[c] != 0 && mine[c] == 0 ? 1 : 0;
      if (own < cells(s.min_face_length_m))
        for (int c = c0; c < c1; ++c) occ[c] = mine[c] != 0 ? 0 : occ[c];
      c0 = c1;
    }
  }
}

// Collinear pieces of one wall line that walls_of kept apart (a drifting
// map's wall, its faces a little more than collinear_offset_m apart
// across), joined across a door-wide gap with free space through it: the
// gap is their doorway.
void join_across_doorways(const OccupancyGrid& grid, std::vector<Piece>& pieces, const FloorPlanSettings& s) {
  for (bool again = true; again;) {
    again = false;
    for (std::size_t i = 0; i < pieces.size() && !again; ++i)
      for (std::size_t j = 0; j < pieces.size() && !again; ++j) {
        Piece& p = pieces[i];
        const Piece& q = pieces[j];
        if (j == i || std::abs(p.d.dot(q.d)) < std::cos(s.angle_tolerance_rad)) continue;
        const Eigen::Vector2d e0 = q.d * q.a0 + q.n * q.offset, e1 = q.d * q.a1 + q.n * q.offset;
        if (std::max(std::abs(p.n.dot(e0) - p.offset), std::abs(p.n.dot(e1) - p.offset)) > 2 * s.collinear_offset_m)
          continue;
        const double q0 = std::min(p.d.dot(e0), p.d.dot(e1)), q1 = std::max(p.d.dot(e0), p.d.dot(e1));
        const double gap = q0 - p.a1;
        if (gap < s.door_min_width_m || gap > s.door_max_width_m + 2 * grid.resolution_m) continue;
        if (!doorway(grid, p, p.a1, q0, s)) continue;
        p.doorways.emplace_back(p.a1, q0);
        for (const auto& [g0, g1] : q.doorways) {
          const double b0 = p.d.dot(q.d * g0 + q.n * q.offset), b1 = p.d.dot(q.d * g1 + q.n * q.offset);
          p.doorways.emplace_back(std::min(b0, b1), std::max(b0, b1));
        }
        std::sort(p.doorways.begin(), p.doorways.end());
        p.a1 = q1;
        p.cells += q.cells;
        p.thickness = std::max(p.thickness, q.thickness);
        p.both_faces = p.both_faces || q.both_faces;
        pieces.erase(pieces.begin() + static_cast<std::ptrdiff_t>(j));
        again = true;
      }
  }
}

// A wall crossing wall `p`'s line near its end at along `a`: the along of
// the crossing of their centre lines, and the crossing wall's thickness.
struct Crossing {
  double at = 0, thickness = 0;
  int side = 0;  // +1 / -1: the crossing wall lies on that side of p's line only (it ends there); 0: both
};

// The crossings of p's line by the walls that pass within `reach` (plus
// their half thickness) of it at their own ends, with `outward` the
// direction away from p (+1 past a1, -1 before a0).
std::vector<Crossing> crossings(const Piece& p, const std::vector<Piece>& all, double reach) {
  std::vector<Crossing> out;
  for (const Piece& q : all) {
    const double cross = p.d.dot(q.n);
    if (std::abs(cross) < std::sin(30.0 * kPi / 180.0)) continue;
    // Along p's line, where q's offset is q.offset.
    const double t = (q.offset - q.n.dot(p.n * p.offset)) / cross;
    const double qa = q.d.dot(p.d * t + p.n * p.offset);
    if (qa < q.a0 - reach - q.thickness / 2 || qa > q.a1 + reach + q.thickness / 2) continue;
    // Which side of p's line q's two ends lie on (beyond a corner's reach).
    const double o0 = p.n.dot(q.d * q.a0 + q.n * q.offset) - p.offset;
    const double o1 = p.n.dot(q.d * q.a1 + q.n * q.offset) - p.offset;
    const double r = reach + p.thickness / 2;
    const int side = std::min(o0, o1) > -r ? 1 : std::max(o0, o1) < r ? -1 : 0;
    out.push_back({t, q.thickness, side});
  }
  return out;
}

// Whether a wall lies on p's line (parallel, centre lines within twice
// collinear_offset_m) starting within corner_gap_m past along `at`.
bool continues(const Piece& p, const std::vector<Piece>& all, double at, int outward, const FloorPlanSettings& s) {
  for (const Piece& q : all) {
    if (std::abs(p.d.dot(q.d)) < std::cos(s.angle_tolerance_rad)) continue;
    const Eigen::Vector2d e0 = q.d * q.a0 + q.n * q.offset, e1 = q.d * q.a1 + q.n * q.offset;
    if (std::abs(p.n.dot((e0 + e1) / 2) - p.offset) > 2 * s.collinear_offset_m) continue;
    const double near = outward > 0 ? std::min(p.d.dot(e0), p.d.dot(e1)) : std::max(p.d.dot(e0), p.d.dot(e1));
    if (std::abs(near - at) <= s.corner_gap_m) return true;
  }
  return false;
}

// Whether `x` lies in wall q's box (its centre line lengthened by half its
// thickness at each end, half its thickness either side), grown by `margin`.
bool inside(const Piece& q, const Eigen::Vector2d& x, double margin) {
  const double a = q.d.dot(x), o = q.n.dot(x) - q.offset, h = q.thickness / 2 + margin;
  return a >= q.a0 - h && a <= q.a1 + h && std::abs(o) <= h;
}

// Whether another wall's box reaches into the passage through doorway g of
// wall p (one of `walls`): the middle of the gap, door_clearance_m out
// either side.
bool blocked(const std::vector<Piece>& walls, const Piece& p, const std::pair<double, double>& g,
             const FloorPlanSettings& s) {
  const double w = g.second - g.first, reach = p.thickness / 2 + s.door_clearance_m;
  for (double a = g.first + w / 5; a <= g.second - w / 5; a += 0.05)
    for (double o = -reach; o <= reach; o += 0.05)
      for (const Piece& q : walls)
        if (&q != &p && inside(q, p.d * a + p.n * (p.offset + o), 0.0)) return true;
  return false;
}

// Whether occupied cells reach door_jamb_m from wall p's line at along
// `x` .. x + 2 cells outward, on door_jamb_solid of the steps at least:
// along the line (the wall goes on, in pieces too short to be walls; or
// past a post, a gap narrower than a door and then on for twice a jamb's
// length: a door's frame post beside a see-through side pane, the wall
// beyond it no wall across the way), or across it to one side only (a
// stub: a wall's end too short to be a wall, or a door frame's return; a
// wall across the line to both sides is a passage round a corner, not a
// jamb).
bool grid_jamb(const OccupancyGrid& grid, const Piece& p, double x, int outward, const FloorPlanSettings& s) {
  const double res = grid.resolution_m, t = p.thickness / 2;
  const auto solid_from = [&](double from, double length) {
    const double lo = std::min(from, from + outward * length), hi = std::max(from, from + outward * length);
    return solid_share(grid, p, lo, hi) >= s.door_jamb_solid;
  };
  if (solid_from(x, s.door_jamb_m)) return true;
  double post = x;  // the post's last solid cross-section, then the pane's far side
  while (solid_across(grid, p, post + outward * res)) post += outward * res;
  for (double y = post + outward * res; outward * (y - post) < s.door_min_width_m; y += outward * res)
    if (solid_across(grid, p, y)) {
      if (solid_from(y, 2 * s.door_jamb_m)) return true;
      break;
    }
  const auto reach = [&](int side) {  // the share of steps out to side with an occupied cell
    int solid = 0, all = 0;
    for (double o = t + res; o <= t + s.door_jamb_m; o += res, ++all) {
      bool hit = false;
      for (double a = x; outward * (a - x) <= 2 * res && !hit; a += outward * res)
        hit = state_at(grid, a * p.d + (p.offset + side * o) * p.n) == CellState::Occupied;
      solid += hit ? 1 : 0;
    }
    return all == 0 ? 0.0 : solid / static_cast<double>(all);
  };
  const double minus = reach(-1), plus = reach(+1);
  return std::max(minus, plus) >= s.door_jamb_solid && std::min(minus, plus) < 1.0 - s.door_jamb_solid;
}

// A doorway past wall p's free end at along `a` (outward: +1 at a1, -1 at
// a0) seen on the grid itself, where no wall piece stands at its far side:
// p's cells going on past the end across gaps narrower than a door (a
// dotted end its faces left out; door_max_width_m at most), then a gap a
// door wide, then a solid cross-section that is a jamb (grid_jamb); none
// of it in another wall of `all` (where one stands, meeting has had its
// say: a corner, or a passage round one; p found again in another
// direction's frame, shorter, does not count) and no wall in its passage
// (blocked). It is held to a doorway beside a corner (free cells
// corner_door_min_depth_m deep on both sides). The new end (in the far
// jamb) and the doorway's g0..g1; or NaN.
double grid_doorway(const OccupancyGrid& grid, const Piece& p, double a, int outward, const std::vector<Piece>& all,
                    const FloorPlanSettings& s, std::pair<double, double>& door) {
  const double res = grid.resolution_m, step = res / 2;
  // A wall in p's direction over p's own stretch, shorter than p: p found
  // again from another direction's frame, that without_duplicates drops.
  const auto again = [&](const Piece& q) {
    if (std::abs(p.d.dot(q.d)) < std::cos(2 * s.angle_tolerance_rad) || q.a1 - q.a0 >= p.a1 - p.a0) return false;
    const double b0 = p.d.dot(q.d * q.a0 + q.n * q.offset), b1 = p.d.dot(q.d * q.a1 + q.n * q.offset);
    return std::min(std::max(b0, b1), p.a1) - std::max(std::min(b0, b1), p.a0) >= (q.a1 - q.a0) / 2;
  };
  const auto in_a_wall = [&](double x) {
    const Eigen::Vector2d at = p.d * x + p.n * p.offset;
    return std::any_of(all.begin(), all.end(), [&](const Piece& q) { return &q != &p && inside(q, at, res) && !again(q); });
  };
  double end = a;  // the last solid cross-section of p's own cells
  for (double x = a + outward * step; outward * (x - end) <= s.door_max_width_m + 2 * res + step; x += outward * step) {
    if (in_a_wall(x)) break;
    if (!solid_across(grid, p, x)) continue;
    const double gap = outward * (x - end) - step;
    if (gap < s.door_min_width_m) {
      if (outward * (x - a) > s.door_max_width_m) return std::numeric_limits<double>::quiet_NaN();
      end = x;
      continue;
    }
    const double near = end + outward * step / 2, far = x - outward * step / 2;
    const double g0 = std::min(near, far), g1 = std::max(near, far);
    if (in_a_wall(x + outward * res) || !grid_jamb(grid, p, x, outward, s) ||
        !doorway(grid, p, g0, g1, s, outward > 0, outward < 0, true) || blocked(all, p, {g0, g1}, s))
      break;
    door = {g0, g1};
    return x + outward * res;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

// Where wall `p`'s end at along `a` (outward: +1 at a1, -1 at a0) meets a
// crossing wall within corner_gap_m; or, as a doorway, a crossing wall a
// door's width beyond it with free space through the gap: the new end (on
// the crossing wall's centre line), and the doorway's g0..g1 when it is
// one. Neither: NaN.
double meeting(const OccupancyGrid& grid, const Piece& p, double a, int outward, const std::vector<Piece>& all,
               const FloorPlanSettings& s, std::pair<double, double>& door) {
  double best = std::numeric_limits<double>::quiet_NaN(), best_dist = 1e300;
  for (const Crossing& c : crossings(p, all, s.corner_gap_m)) {
    const double dist = std::abs(c.at - a);
    if (dist <= s.corner_gap_m + c.thickness / 2 && dist < best_dist) best = c.at, best_dist = dist;
  }
  // From the end (or the corner's far face) to the next crossing wall: a
  // doorway when door-wide with free space through it and p's line going
  // on past the crossing wall (a gap in a wall line; a gap between a
  // wall's end and a wall across its way is a passage round a corner, as
  // in the truth files' rule). Beyond a corner only between two walls
  // leaving p's line to the same side (a corridor's mouth in a hall's wall).
  double from = a, corner = best;
  int corner_side = 0;
  if (!std::isnan(best)) {
    for (const Crossing& c : crossings(p, all, s.corner_gap_m))
      if (c.at == best) from = c.at + outward * c.thickness / 2, corner_side = c.side;
    if (corner_side == 0) return best;
    best_dist = 1e300;
  }
  for (const Crossing& c : crossings(p, all, 0.0)) {
    // p's line goes on past c, or c ends on p's line (its end is the far
    // jamb: a gap beside a corner, held to a room's depth, not a niche's).
    const bool beside_corner = !continues(p, all, c.at, outward, s);
    if ((corner_side != 0 && c.side != corner_side) || (c.side == 0 && beside_corner)) continue;
    const double gap = outward * (c.at - from) - c.thickness / 2;  // clear width from the end to its face
    if (gap < s.door_min_width_m || gap > s.door_max_width_m + 2 * grid.resolution_m || gap >= best_dist) continue;
    const double g0 = outward > 0 ? from : c.at + c.thickness / 2, g1 = outward > 0 ? c.at - c.thickness / 2 : from;
    if (!doorway(grid, p, g0, g1, s, outward > 0 && std::isnan(corner), outward < 0 && std::isnan(corner), beside_corner))
      continue;
    best = c.at, best_dist = gap, door = {g0, g1};
  }
  if (std::isnan(best) && std::isnan(corner)) return grid_doorway(grid, p, a, outward, all, s, door);
  return best;
}

// Whether another wall lies on wall i's line (parallel, centre lines within
// twice collinear_offset_m) less than a door's width and two corner gaps
// beyond one of its ends: a piece of a wall line broken by doorways.
bool in_line(const std::vector<Piece>& all, std::size_t i, const FloorPlanSettings& s) {
  const Piece& p = all[i];
  for (std::size_t j = 0; j < all.size(); ++j) {
    const Piece& q = all[j];
    if (j == i || std::abs(p.d.dot(q.d)) < std::cos(s.angle_tolerance_rad)) continue;
    const double sign = p.d.dot(q.d) > 0 ? 1.0 : -1.0;
    const double q0 = p.d.dot(q.d * (sign > 0 ? q.a0 : q.a1) + q.n * q.offset);
    const double q1 = p.d.dot(q.d * (sign > 0 ? q.a1 : q.a0) + q.n * q.offset);
    const double off = p.n.dot(q.d * ((q.a0 + q.a1) / 2) + q.n * q.offset) - p.offset;
    if (std::abs(off) > 2 * s.collinear_offset_m) continue;
    const double gap = std::max(q0 - p.a1, p.a0 - q1);
    if (gap <= s.door_max_width_m + 2 * s.corner_gap_m) return true;
  }
  return false;
}

// A wall found twice (a wall between two dominant directions is a face in
// both) is kept once, the longer; a wall's other face beside it (nothing
// free between) makes it one thicker wall; a doorway another wall's box
// reaches into is no doorway (the world would have wall in it).
std::vector<Piece> without_duplicates(const OccupancyGrid& grid, std::vector<Piece> pieces,
                                      const FloorPlanSettings& s) {
  std::sort(pieces.begin(), pieces.end(), [](const Piece& a, const Piece& b) { return a.a1 - a.a0 > b.a1 - b.a0; });
  std::vector<Piece> kept;
  for (const Piece& p : pieces) {
    bool twice = false;
    for (Piece& q : kept) {
      if (twice || std::abs(p.d.dot(q.d)) < std::cos(2 * s.angle_tolerance_rad)) continue;
      // The share of p's centre line inside q's box; or close beside it
      // with no free cell between: q's other face, the two faces of a wall
      // thicker than the faces could join at.
      int in = 0, behind = 0, all = 0;
      for (double a = p.a0; a <= p.a1; a += 0.05, ++all) {
        const Eigen::Vector2d x = p.d * a + p.n * p.offset;
        if (inside(q, x, 0.05)) {
          ++in;
        } else if (inside(q, x, s.max_wall_thickness_m)) {
          const Eigen::Vector2d y = x - q.n * (q.n.dot(x) - q.offset);  // x's foot on q's line
          const double len = (y - x).norm();
          bool clear = true;
          for (double t = 0; t <= len && clear; t += grid.resolution_m)
            clear = state_at(grid, x + (y - x) * (t / len)) != CellState::Free;
          behind += clear ? 1 : 0;
        }
      }
      twice = in >= 0.7 * all || in + behind >= 0.7 * all;
      if (!twice || behind <= in) continue;
      // One wall between the outer sides of the two faces (p's mid-point across q's line).
      const double po = q.n.dot(p.d * ((p.a0 + p.a1) / 2) + p.n * p.offset);
      const double lo = std::min(q.offset - q.thickness / 2, po - p.thickness / 2);
      const double hi = std::max(q.offset + q.thickness / 2, po + p.thickness / 2);
      q.offset = (lo + hi) / 2, q.thickness = hi - lo, q.both_faces = true;
    }
    if (!twice) kept.push_back(p);
  }
  for (std::size_t i = 0; i < kept.size(); ++i) {
    auto& doors = kept[i].doorways;
    doors.erase(std::remove_if(doors.begin(), doors.end(),
                               [&](const std::pair<double, double>& g) { return blocked(kept, kept[i], g, s); }),
                doors.end());
  }
  return kept;
}

// Inside wall q's box (inside()) and not in one of its doorways: solid as
// the world builds it (sim::wall_boxes).
bool in_solid(const Piece& q, const Eigen::Vector2d& x) {
  if (!inside(q, x, 0.0)) return false;
  const double a = q.d.dot(x);
  return std::none_of(q.doorways.begin(), q.doorways.end(), [&](const std::pair<double, double>& g) {
    return g.first > q.a0 && g.second < q.a1 && a > g.first && a < g.second;
  });
}

// Each doorway narrowed to its clear width: the widest stretch of its gap
// whose cross-section through the wall's slab no other wall's box reaches
// into (a wall meeting the doorway's jamb, its box lengthened past its
// line, stands in the gap); one left narrower than door_min_width_m is
// closed.
void clear_doorways(std::vector<Piece>& walls, const FloorPlanSettings& s) {
  constexpr double kStep = 0.005;
  std::vector<std::vector<std::pair<double, double>>> cleared(walls.size());
  for (std::size_t i = 0; i < walls.size(); ++i) {
    const Piece& p = walls[i];
    for (const auto& [g0, g1] : p.doorways) {
      const int n = static_cast<int>(std::floor((g1 - g0) / kStep));
      const auto open_at = [&](int k) {
        const double a = g0 + k * (g1 - g0) / n;
        for (double v = -0.4; v <= 0.41; v += 0.2) {
          const Eigen::Vector2d x = p.d * a + p.n * (p.offset + v * p.thickness);
          for (std::size_t q = 0; q < walls.size(); ++q)
            if (q != i && in_solid(walls[q], x)) return false;
        }
        return true;
      };
      int best0 = 0, best1 = -1;
      for (int k = 0, run = -1; k <= n; ++k) {
        if (!open_at(k)) {
          run = -1;
          continue;
        }
        if (run < 0) run = k;
        if (k - run > best1 - best0) best0 = run, best1 = k;
      }
      const double c0 = g0 + best0 * (g1 - g0) / n, c1 = g0 + best1 * (g1 - g0) / n;
      if (best1 < 0 || (c1 - c0 < s.door_min_width_m && c1 - c0 < g1 - g0)) continue;
      cleared[i].emplace_back(c0, c1);
    }
  }
  for (std::size_t i = 0; i < walls.size(); ++i) walls[i].doorways = std::move(cleared[i]);
}

}  // namespace

Segmentation segment_floor_plan(const OccupancyGrid& grid, const FloorPlanSettings& s) {
  if (grid.width <= 0 || grid.height <= 0 || grid.cells.size() != static_cast<std::size_t>(grid.width) * grid.height)
    throw std::invalid_argument("segment_floor_plan: empty or inconsistent grid");
  const Masks masks = masks_of(grid);
  const int n_free = cv::countNonZero(masks.free);
  if (n_free == 0 || cv::countNonZero(masks.occupied) == 0)
    throw std::invalid_argument("segment_floor_plan: the grid has no free or no occupied cells");

  Segmentation seg;
  seg.floor.height_m = 0.0;
  seg.floor.points = n_free;
  std::vector<cv::Point> free_px;
  cv::findNonZero(masks.free, free_px);
  const cv::Rect box = cv::boundingRect(free_px);
  seg.floor.min_m = grid.origin_m + grid.resolution_m * Eigen::Vector2d(box.x, box.y);
  seg.floor.max_m = grid.origin_m + grid.resolution_m * Eigen::Vector2d(box.x + box.width, box.y + box.height);

  std::vector<Piece> pieces;
  const auto directions = wall_directions(masks.occupied, s);
  std::vector<double> thetas;
  for (const auto& direction : directions) thetas.push_back(direction.first);
  Masks slanted{cv::Mat(), masks.free, masks.unknown};
  slanted_walls(grid, masks.occupied, thetas, s, pieces, slanted.occupied);
  const bool any_slanted = !pieces.empty();
  for (const auto& [theta, share] : directions) {
    // A minor direction (a building's one slanted wall) holds long walls only: its short runs are clutter.
    FloorPlanSettings in_direction = s;
    if (share < s.min_direction_share) in_direction.min_wall_length_m = s.minor_wall_min_length_m;
    Frame f = turned(grid, masks, theta);
    if (any_slanted) without_slanted(f, turned(grid, slanted, theta), s);
    walls_of(grid, f, in_direction, pieces);
  }

  join_across_doorways(grid, pieces, s);
  // Ends meet the crossing wall's centre line; a free end stops half a
  // thickness short of the last occupied cell (the world file's box
  // reaches thickness/2 past its line's ends).
  std::vector<Piece> met = pieces;
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    const Piece& p = pieces[i];
    std::pair<double, double> door0{0, 0}, door1{0, 0};
    const double m0 = meeting(grid, p, p.a0, -1, pieces, s, door0), m1 = meeting(grid, p, p.a1, +1, pieces, s, door1);
    met[i].a0 = std::isnan(m0) ? p.a0 + p.thickness / 2 : m0;
    met[i].a1 = std::isnan(m1) ? p.a1 - p.thickness / 2 : m1;
    met[i].joined = !std::isnan(m0) || !std::isnan(m1) || in_line(pieces, i, s);
    // A doorway between a wall's end and the wall it meets: its gap is part of the wall line.
    if (door0.second > door0.first) met[i].doorways.insert(met[i].doorways.begin(), door0);
    if (door1.second > door1.first) met[i].doorways.push_back(door1);
  }
  met = without_duplicates(grid, std::move(met), s);
  std::erase_if(met, [&](const Piece& p) {
    if (p.a1 - p.a0 < s.min_wall_length_m - p.thickness) return true;
    // A short wall standing free, touching no other, is furniture or
    // clutter: short by its solid length (desks in a row are no wall with doorways).
    double solid = p.a1 - p.a0;
    for (const auto& [g0, g1] : p.doorways) solid -= g1 - g0;
    return !p.joined && solid < s.free_wall_min_length_m;
  });
  clear_doorways(met, s);
  for (const Piece& p : met) {
    Wall w;
    w.from_m = p.d * p.a0 + p.n * p.offset;
    w.to_m = p.d * p.a1 + p.n * p.offset;
    w.height_m = s.wall_height_m;
    w.thickness_m = p.thickness;
    w.both_faces_seen = p.both_faces;
    w.points = p.cells;
    const int index = static_cast<int>(seg.walls.size());
    for (const auto& [g0, g1] : p.doorways) {
      if (g0 <= p.a0 || g1 >= p.a1) continue;
      w.openings.push_back({g0 - p.a0, g1 - g0, s.door_height_m});
      Door door;
      door.center_m = p.d * ((g0 + g1) / 2) + p.n * p.offset;
      door.yaw_rad = std::atan2(p.d.y(), p.d.x());
      door.width_m = g1 - g0;
      door.height_m = s.door_height_m;
      door.wall_thickness_m = p.thickness;
      door.lintel = true;
      door.wall = index;
      seg.doors.push_back(door);
    }
    seg.walls.push_back(std::move(w));
  }
  return seg;
}

}  // namespace rise::semantic
