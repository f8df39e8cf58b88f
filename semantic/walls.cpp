// Walls and doors (seed paper, section 3): the points between floor and
// ceiling projected onto the floor plane give an occupancy image of the
// tall vertical structure; its Hough lines (cv::HoughLines) seed vertical
// planes refined by least squares on their inlier points; two parallel faces
// a wall's thickness apart are the two sides of one wall; gaps of door width
// with wall above them ("wall above door") or a panel in them are doors.

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <tuple>

#include "semantic/floor_plan.hpp"
#include "semantic/segmentation_internal.hpp"

namespace rise::semantic::detail {
namespace {

constexpr double kSliceM = 0.1;   // tall cells: vertical coverage in slices of this

using Run = std::pair<double, double>;

// Runs along a line of points (along, offset from the line): 5 cm bins
// whose points centre on the line — the tail of a parallel surface a few
// cm away (a door panel behind the face) has them all to one side — joined
// over gaps up to gap_m; runs shorter than min_len_m dropped.
std::vector<Run> runs_of(std::vector<std::pair<double, double>> pts, double gap_m, double min_len_m,
                         double inlier_m) {
  std::vector<Run> out;
  if (pts.empty()) return out;
  std::sort(pts.begin(), pts.end());
  constexpr double kBin = 0.05;
  const double lo = pts.front().first;
  const auto bin = [&](double a) { return static_cast<std::size_t>((a - lo) / kBin); };
  std::vector<double> sum(bin(pts.back().first) + 1, 0.0);
  std::vector<int> count(sum.size(), 0);
  for (const auto& [a, o] : pts) {
    sum[bin(a)] += o;
    ++count[bin(a)];
  }
  std::vector<double> kept;
  for (const auto& [a, o] : pts)
    if (std::abs(sum[bin(a)] / count[bin(a)]) <= 0.5 * inlier_m) kept.push_back(a);
  if (kept.empty()) return out;
  Run cur{kept[0], kept[0]};
  for (std::size_t i = 1; i <= kept.size(); ++i) {
    if (i == kept.size() || kept[i] - cur.second > gap_m) {
      if (cur.second - cur.first >= min_len_m) out.push_back(cur);
      if (i < kept.size()) cur = {kept[i], kept[i]};
    } else {
      cur.second = kept[i];
    }
  }
  return out;
}

std::vector<Run> merge_runs(std::vector<Run> runs, double gap_m) {
  std::sort(runs.begin(), runs.end());
  std::vector<Run> out;
  for (const auto& r : runs) {
    if (!out.empty() && r.first - out.back().second <= gap_m)
      out.back().second = std::max(out.back().second, r.second);
    else
      out.push_back(r);
  }
  return out;
}

double total_length(const std::vector<Run>& runs) {
  double sum = 0;
  for (const auto& r : runs) sum += r.second - r.first;
  return sum;
}

double overlap(const std::vector<Run>& a, const std::vector<Run>& b) {
  double sum = 0;
  for (const auto& x : a)
    for (const auto& y : b) sum += std::max(0.0, std::min(x.second, y.second) - std::max(x.first, y.first));
  return sum;
}

// Runs of `runs` (in `from`'s along coordinate) in `to`'s along coordinate.
std::vector<Run> reproject(const std::vector<Run>& runs, const Line2& from, const Line2& to) {
  std::vector<Run> out;
  for (const auto& r : runs) {
    const double a = to.along(from.point + from.direction * r.first);
    const double b = to.along(from.point + from.direction * r.second);
    out.push_back({std::min(a, b), std::max(a, b)});
  }
  return out;
}

// One side of a wall: a vertical plane through `line`, seen over `runs`.
struct Face {
  Line2 line;
  std::vector<Run> runs;
  int points = 0;
};

// A wall's centre line with everything seen along it.
struct WallLine {
  Line2 line;
  double thickness_m = 0;
  bool both = false;
  std::vector<Run> runs;
  int points = 0;
};

bool parallel(const Line2& a, const Line2& b, double tol_rad) {
  return std::abs(a.direction.dot(b.normal)) < std::sin(tol_rad);
}

// The cells (row-major, nx × ny cells of `cell` from `lo`) of tall
// vertical structure: holding points, and together with the cells within
// `radius` of them reaching over the wall band zlo..zhi (wall_min_tall_m of
// it, or 60 % of a lower band): a far wall's points lie on scan lines a few
// cells apart, on a few columns of rays.
std::vector<char> tall_cells(const std::vector<Eigen::Vector2d>& xy, const std::vector<double>& z, double zlo,
                             double zhi, const Eigen::Vector2d& lo, double cell, int nx, int ny, int radius,
                             const SegmentationSettings& s) {
  const int slices = std::clamp(static_cast<int>(std::ceil((zhi - zlo) / kSliceM)), 1, 64);
  const int need = std::max(1, std::min(static_cast<int>(std::lround(s.wall_min_tall_m / kSliceM)),
                                        static_cast<int>(std::ceil(0.6 * slices))));
  std::vector<uint64_t> mask(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny), 0);
  for (std::size_t i = 0; i < xy.size(); ++i) {
    const int c = static_cast<int>((xy[i].x() - lo.x()) / cell), r = static_cast<int>((xy[i].y() - lo.y()) / cell);
    if (c < 0 || r < 0 || c >= nx || r >= ny) continue;
    const int k = std::clamp(static_cast<int>((z[i] - zlo) / kSliceM), 0, slices - 1);
    mask[static_cast<std::size_t>(r) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(c)] |= uint64_t{1} << k;
  }
  // From the lowest to the highest slice seen around the cell.
  const auto span = [](uint64_t m) { return m ? 64 - std::countl_zero(m) - std::countr_zero(m) : 0; };
  std::vector<char> tall(mask.size(), 0);
  for (int r = 0; r < ny; ++r)
    for (int c = 0; c < nx; ++c) {
      const std::size_t i = static_cast<std::size_t>(r) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(c);
      if (mask[i] == 0) continue;
      uint64_t m = 0;
      for (int dr = -radius; dr <= radius; ++dr)
        for (int dc = -radius; dc <= radius; ++dc) {
          const int rr = r + dr, cc = c + dc;
          if (rr >= 0 && rr < ny && cc >= 0 && cc < nx)
            m |= mask[static_cast<std::size_t>(rr) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(cc)];
        }
      tall[i] = span(m) >= need;
    }
  return tall;
}

std::vector<Face> find_faces(const std::vector<Eigen::Vector2d>& xy, const std::vector<double>& z, double zlo,
                             double zhi, const SegmentationSettings& s) {
  std::vector<Face> faces;
  if (xy.empty()) return faces;
  Eigen::Vector2d lo = xy[0], hi = xy[0];
  for (const auto& p : xy) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double cell = s.cell_m;
  check_grid(hi - lo, cell, "the wall band");
  const int nx = static_cast<int>((hi.x() - lo.x()) / cell) + 1, ny = static_cast<int>((hi.y() - lo.y()) / cell) + 1;
  const auto is_tall = tall_cells(xy, z, zlo, zhi, lo, cell, nx, ny, 2, s);
  const auto cell_of = [&](const Eigen::Vector2d& p) {
    return static_cast<std::size_t>(static_cast<int>((p.y() - lo.y()) / cell)) * static_cast<std::size_t>(nx) +
           static_cast<std::size_t>(static_cast<int>((p.x() - lo.x()) / cell));
  };
  const auto tall = [&](std::size_t i) { return is_tall[i] != 0; };
  cv::Mat1b image(ny, nx, uchar{0});
  for (int r = 0; r < ny; ++r)
    for (int c = 0; c < nx; ++c)
      if (tall(static_cast<std::size_t>(r) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(c))) image(r, c) = 255;
  // The points of tall cells are the wall candidates.
  std::vector<Eigen::Vector2d> pts;
  for (const auto& p : xy)
    if (tall(cell_of(p))) pts.push_back(p);
  std::vector<char> used(pts.size(), 0);

  std::vector<cv::Vec2f> lines;
  const int votes = std::max(8, static_cast<int>(s.wall_min_length_m / cell));
  cv::HoughLines(image, lines, 1.0, CV_PI / 360.0, votes);
  const int max_lines = std::min<int>(static_cast<int>(lines.size()), 400);
  for (int li = 0; li < max_lines; ++li) {
    const double rho = lines[static_cast<std::size_t>(li)][0], theta = lines[static_cast<std::size_t>(li)][1];
    // Pixel (c, r) is world lo + (c + 0.5, r + 0.5)·cell.
    Line2 line;
    line.normal = {std::cos(theta), std::sin(theta)};
    line.direction = {-line.normal.y(), line.normal.x()};
    const double d = rho * cell + line.normal.dot(lo + Eigen::Vector2d(0.5 * cell, 0.5 * cell));
    line.point = line.normal * d;
    std::vector<Run> runs;
    std::vector<std::size_t> members;
    for (int pass = 0; pass < 3; ++pass) {
      std::vector<double> along;
      std::vector<std::pair<double, double>> along_offset;
      std::vector<std::size_t> near;
      for (std::size_t i = 0; i < pts.size(); ++i)
        if (!used[i] && std::abs(line.offset(pts[i])) < s.wall_inlier_m) {
          near.push_back(i);
          along.push_back(line.along(pts[i]));
          along_offset.push_back({along.back(), line.offset(pts[i])});
        }
      runs = runs_of(along_offset, s.wall_merge_gap_m, s.wall_min_length_m, s.wall_inlier_m);
      members.clear();
      std::vector<Eigen::Vector2d> fit;
      for (std::size_t k = 0; k < near.size(); ++k)
        for (const auto& r : runs)
          if (along[k] >= r.first && along[k] <= r.second) {
            members.push_back(near[k]);
            fit.push_back(pts[near[k]]);
            break;
          }
      if (fit.size() < 30 || pass == 2) break;  // the last runs are along the last line
      line = fit_line(fit);                     // the vertical plane through the inliers
    }
    if (members.size() < 30 || total_length(runs) < s.wall_min_length_m) continue;
    for (std::size_t i : members) used[i] = 1;
    faces.push_back({line, runs, static_cast<int>(members.size())});
  }
  return faces;
}

// Floor points beside a face on each side (+normal, −normal): the room is
// on the side where the floor is seen.
std::pair<int, int> floor_beside(const Face& f, const std::vector<Eigen::Vector2d>& floor_xy) {
  int pos = 0, neg = 0;
  const double s0 = f.runs.front().first, s1 = f.runs.back().second;
  for (const auto& p : floor_xy) {
    const double a = f.line.along(p);
    if (a < s0 || a > s1) continue;
    const double o = f.line.offset(p);
    if (o > 0.1 && o < 0.6) ++pos;
    if (o < -0.1 && o > -0.6) ++neg;
  }
  return {pos, neg};
}

// Whether the floor is seen on both sides of the wall (centre line `line`,
// faces `half_m` from it) through the gap g0..g1: in 10 cm cells up to 1 m
// from each face.
bool floor_through(const Line2& line, double half_m, double g0, double g1, const std::vector<Eigen::Vector2d>& floor_xy,
                   const SegmentationSettings& s) {
  std::vector<std::pair<long long, long long>> cells[2];
  for (const auto& p : floor_xy) {
    const double a = line.along(p), o = line.offset(p);
    if (a < g0 + 0.05 || a > g1 - 0.05 || std::abs(o) < half_m + 0.05 || std::abs(o) > half_m + 1.0) continue;
    cells[o > 0].push_back({static_cast<long long>(std::floor(a / 0.1)), static_cast<long long>(std::floor(o / 0.1))});
  }
  for (auto& c : cells) {
    std::sort(c.begin(), c.end());
    if (std::unique(c.begin(), c.end()) - c.begin() < s.door_min_floor_cells) return false;
  }
  return true;
}

// Whether the stretch `runs` of `line` lies within the wall's slab and extent.
bool contains(const WallLine& w, const Line2& line, const std::vector<Run>& runs, double inlier_m) {
  const double half = w.thickness_m / 2 + 2 * inlier_m;  // the noise tails of its faces too
  const double lo = w.runs.front().first - inlier_m, hi = w.runs.back().second + inlier_m;
  const auto in = [&](double a) {
    const Eigen::Vector2d e = line.point + line.direction * a;
    return std::abs(w.line.offset(e)) <= half && w.line.along(e) >= lo && w.line.along(e) <= hi;
  };
  return in(runs.front().first) && in(runs.back().second);
}

// Lines side by side with no floor seen between them over their common
// stretch are one wall: a slab of points (a voxel map's thick wall with
// the shelves along it, a noisy sensor's wall) is found as several
// parallel faces a few centimetres apart, and a drifting map's as faces a
// few degrees apart (slab_tolerance_rad). A pair of like length whose
// joint slab is at most slab_max_thickness_m thick becomes one line through
// the slab's middle; a thicker pair, or one less than half the other's
// length, whose faces are at most slab_against_m apart is a wall and what
// stands against it (shelves, a cupboard): the shorter goes.
void merge_side_by_side(std::vector<WallLine>& walls, const std::vector<Eigen::Vector2d>& floor_xy,
                        const SegmentationSettings& s) {
  std::sort(walls.begin(), walls.end(), [](const WallLine& a, const WallLine& b) { return a.points > b.points; });
  for (bool again = true; again;) {
    again = false;
    for (std::size_t j = walls.size(); j-- > 0 && !again;)
      for (std::size_t i = 0; i < j && !again; ++i) {
        WallLine& w = walls[i];
        const WallLine& v = walls[j];
        if (!parallel(w.line, v.line, s.slab_tolerance_rad)) continue;
        const auto rv = reproject(v.runs, v.line, w.line);
        const double ov = overlap(w.runs, rv);
        if (ov < 0.5 * std::min(total_length(w.runs), total_length(v.runs))) continue;
        // v's centre line across w's, at the ends of their common stretch.
        const double a0 = std::max(w.runs.front().first, rv.front().first);
        const double a1 = std::min(w.runs.back().second, rv.back().second);
        const auto across = [&](double a) {
          const Eigen::Vector2d on_w = w.line.point + w.line.direction * a;
          const double t = v.line.along(on_w);
          return w.line.offset(v.line.point + v.line.direction * t);
        };
        const double o0 = std::min(across(a0), across(a1)), o1 = std::max(across(a0), across(a1));
        const double lo = std::min(-w.thickness_m / 2, o0 - v.thickness_m / 2);
        const double hi = std::max(w.thickness_m / 2, o1 + v.thickness_m / 2);
        // Floor between their faces: two walls, not one.
        const double g0 = o0 > 0 ? w.thickness_m / 2 : o1 + v.thickness_m / 2;
        const double g1 = o0 > 0 ? o0 - v.thickness_m / 2 : -w.thickness_m / 2;
        if (g1 - g0 > s.slab_against_m) continue;
        int between = 0;
        if (g1 - g0 > 0.05)
          for (const auto& p : floor_xy) {
            const double a = w.line.along(p), o = w.line.offset(p);
            between += a > a0 && a < a1 && o > g0 && o < g1;
          }
        if (between > 0) continue;
        // Too thick together, or v a short thing beside a long wall: what
        // stands against it (shelves, a cupboard) goes, the wall stays as it is.
        if (hi - lo > s.slab_max_thickness_m || total_length(v.runs) < 0.5 * total_length(w.runs)) {
          if (total_length(v.runs) < total_length(w.runs)) {
            w.points += v.points;
            walls.erase(walls.begin() + static_cast<std::ptrdiff_t>(j));
            again = true;
          }
          continue;
        }
        auto runs = w.runs;
        runs.insert(runs.end(), rv.begin(), rv.end());
        w.runs = merge_runs(runs, s.wall_merge_gap_m);
        w.line.point += w.line.normal * ((lo + hi) / 2);
        w.thickness_m = hi - lo;
        w.both = w.both || v.both;
        w.points += v.points;
        walls.erase(walls.begin() + static_cast<std::ptrdiff_t>(j));
        again = true;
      }
  }
}

// Lines off the building's major directions (peaks holding at least
// wall_major_share of the most-walled direction's length, in 1° bins
// smoothed over ±3°, within slab_tolerance_rad) that are shorter than
// wall_off_direction_min_length_m: furniture and clutter at odd angles.
void drop_off_direction(std::vector<WallLine>& walls, const SegmentationSettings& s) {
  constexpr int kBins = 180;
  std::vector<double> hist(kBins, 0.0);
  const auto bin_of = [](const WallLine& w) {
    double a = std::atan2(w.line.direction.y(), w.line.direction.x()) * 180.0 / M_PI;
    a = std::fmod(a + 360.0, 180.0);
    return static_cast<int>(a) % kBins;
  };
  for (const auto& w : walls) hist[static_cast<std::size_t>(bin_of(w))] += total_length(w.runs);
  std::vector<double> smooth(kBins, 0.0);
  for (int i = 0; i < kBins; ++i)
    for (int k = -3; k <= 3; ++k) smooth[static_cast<std::size_t>(i)] += hist[static_cast<std::size_t>(((i + k) % kBins + kBins) % kBins)];
  const double top = *std::max_element(smooth.begin(), smooth.end());
  const int tol = static_cast<int>(std::lround(s.slab_tolerance_rad * 180.0 / M_PI));
  std::vector<WallLine> kept;
  for (const auto& w : walls) {
    const int b = bin_of(w);
    bool major = false;
    for (int k = -tol; k <= tol && !major; ++k) {
      const int i = ((b + k) % kBins + kBins) % kBins;
      // A peak within tol of the line's own direction, strong enough.
      bool peak = smooth[static_cast<std::size_t>(i)] >= s.wall_major_share * top;
      for (int m = 1; m <= 3 && peak; ++m)
        peak = smooth[static_cast<std::size_t>(i)] >= smooth[static_cast<std::size_t>(((i + m) % kBins + kBins) % kBins)] &&
               smooth[static_cast<std::size_t>(i)] >= smooth[static_cast<std::size_t>(((i - m) % kBins + kBins) % kBins)];
      major = peak;
    }
    if (major || total_length(w.runs) >= s.wall_off_direction_min_length_m) kept.push_back(w);
  }
  walls.swap(kept);
}

std::vector<WallLine> build_wall_lines(std::vector<Face> faces, const std::vector<Eigen::Vector2d>& floor_xy,
                                       const SegmentationSettings& s) {
  std::sort(faces.begin(), faces.end(),
            [](const Face& a, const Face& b) { return total_length(a.runs) > total_length(b.runs); });
  struct Pair {
    double distance, overlap_m;
    std::size_t i, j;
  };
  std::vector<Pair> pairs;
  for (std::size_t i = 0; i < faces.size(); ++i)
    for (std::size_t j = i + 1; j < faces.size(); ++j) {
      if (!parallel(faces[i].line, faces[j].line, s.parallel_tolerance_rad)) continue;
      const double d = std::abs(faces[i].line.offset(faces[j].line.point));
      if (d < s.wall_min_thickness_m || d > s.wall_max_thickness_m) continue;
      const auto rj = reproject(faces[j].runs, faces[j].line, faces[i].line);
      const double ov = overlap(faces[i].runs, rj);
      if (ov < 0.5 * std::min(total_length(faces[i].runs), total_length(faces[j].runs))) continue;
      pairs.push_back({d, ov, i, j});
    }
  // The two sides of a wall overlap the most: a stray face close to one
  // side (a panel's scatter) overlaps it less.
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) { return a.overlap_m > b.overlap_m; });
  std::vector<char> taken(faces.size(), 0);
  std::vector<WallLine> walls;
  for (const auto& p : pairs) {
    if (taken[p.i] || taken[p.j]) continue;
    taken[p.i] = taken[p.j] = 1;
    const Face &a = faces[p.i], &b = faces[p.j];
    WallLine w;
    Eigen::Vector2d dir_b = b.line.direction;
    if (dir_b.dot(a.line.direction) < 0) dir_b = -dir_b;
    w.line.direction = (a.line.direction + dir_b).normalized();
    w.line.normal = {-w.line.direction.y(), w.line.direction.x()};
    w.line.point = a.line.point + a.line.normal * (a.line.offset(b.line.point) / 2);
    w.thickness_m = p.distance;
    w.both = true;
    auto runs = reproject(a.runs, a.line, w.line);
    const auto rb = reproject(b.runs, b.line, w.line);
    runs.insert(runs.end(), rb.begin(), rb.end());
    w.runs = merge_runs(runs, s.wall_merge_gap_m);
    w.points = a.points + b.points;
    walls.push_back(w);
  }
  // The same for pairs: two faces of a door panel inside a wall's gap.
  std::sort(walls.begin(), walls.end(), [](const WallLine& a, const WallLine& b) { return a.points > b.points; });
  for (std::size_t j = walls.size(); j-- > 0;)
    for (std::size_t i = 0; i < j; ++i)
      if (contains(walls[i], walls[j].line, walls[j].runs, s.wall_inlier_m)) {
        walls.erase(walls.begin() + static_cast<std::ptrdiff_t>(j));
        break;
      }
  for (std::size_t i = 0; i < faces.size(); ++i) {
    if (taken[i]) continue;
    const Face& f = faces[i];
    // A face inside a wall already found (a door panel, a recess, the
    // scatter of a face) is not a wall of its own.
    bool inside = false;
    for (const auto& w : walls)
      if (contains(w, f.line, f.runs, s.wall_inlier_m)) inside = true;
    if (inside) continue;
    // Seen from one side: the wall lies on the side without floor.
    const auto [pos, neg] = floor_beside(f, floor_xy);
    WallLine w;
    w.line = f.line;
    w.thickness_m = s.default_wall_thickness_m;
    w.line.point += w.line.normal * (pos >= neg ? -1.0 : 1.0) * w.thickness_m / 2;
    w.runs = f.runs;
    w.points = f.points;
    // A face in line with a wall already found extends it.
    bool merged = false;
    for (auto& other : walls) {
      if (!parallel(w.line, other.line, s.parallel_tolerance_rad)) continue;
      if (std::abs(other.line.offset(w.line.point)) > other.thickness_m / 2 + s.wall_inlier_m) continue;
      auto runs = other.runs;
      const auto rw = reproject(w.runs, w.line, other.line);
      runs.insert(runs.end(), rw.begin(), rw.end());
      other.runs = merge_runs(runs, s.wall_merge_gap_m);
      other.points += w.points;
      merged = true;
      break;
    }
    if (!merged) walls.push_back(w);
  }
  drop_off_direction(walls, s);
  merge_side_by_side(walls, floor_xy, s);
  return walls;
}

// A wall segment before corner snapping: [s0, s1] along its wall line.
struct Segment {
  std::size_t line = 0;
  double s0 = 0, s1 = 0;
  std::vector<Opening> openings;  // at_m relative to s0 for now: absolute along positions
  double height_m = 0;
  int points = 0;
};


// A wall's slab in 3D: its points (along from_m, height above the floor)
// below the ceiling; its top (the fifth highest point over its length);
// the cells a gap in it is inspected in: twice the faces' point spacing,
// 5 to 25 cm (a sparse far wall has holes between its points).
struct Slab {
  std::vector<std::pair<double, double>> along_height;
  double top_m = 0, cell_m = 0.05;
};

// The slab's top from the heights of its points on the faces' runs, and
// its cell from their spacing.
void set_top_and_cell(Slab& slab, std::vector<double>& heights, const std::vector<Run>& runs, bool both) {
  std::sort(heights.begin(), heights.end());
  slab.top_m = heights.size() > 5 ? heights[heights.size() - 5] : quantile(heights, 1.0);
  double seen_m2 = 0;
  for (const auto& r : runs) seen_m2 += (r.second - r.first) * std::max(slab.top_m, 0.1) * (both ? 2.0 : 1.0);
  const double spacing_m = std::sqrt(seen_m2 / std::max<double>(1.0, static_cast<double>(heights.size())));
  slab.cell_m = std::clamp(2 * spacing_m, 0.05, 0.25);
}

Slab slab_of(const Cloud& cloud, const Line2& line, double half_m, double a0, double a1, const std::vector<Run>& runs,
             bool both, double z_floor, double z_roof) {
  Slab out;
  std::vector<double> heights;
  for (const auto& p : cloud.points) {
    if (p.z() > z_roof) continue;
    const Eigen::Vector2d xy = p.head<2>().cast<double>();
    if (std::abs(line.offset(xy)) > half_m) continue;
    const double a = line.along(xy);
    if (a < a0 - 0.2 || a > a1 + 0.2) continue;
    out.along_height.push_back({a, p.z() - z_floor});
    for (const auto& r : runs)
      if (a >= r.first && a <= r.second) {
        heights.push_back(p.z() - z_floor);
        break;
      }
  }
  set_top_and_cell(out, heights, runs, both);
  return out;
}

// Walls and doors from segment_floor_plan() on the cloud's wall-band grid
// (see SegmentationSettings::walls_from_floor_plan): one wall per slab, its
// height from its points; a doorway of the plan is a door when doors.cpp
// finds a lintel or a panel in it and no window sill, as in
// find_walls_and_doors; any other doorway is a gap between two walls.
void walls_from_floor_plan(const Cloud& cloud, const SegmentationSettings& s, const Floor& floor, double zlo,
                           double zhi, double z_roof, const std::vector<Eigen::Vector2d>& band_xy,
                           const std::vector<double>& band_z, const std::vector<Eigen::Vector2d>& floor_xy,
                           std::vector<Wall>& walls, std::vector<Door>& doors) {
  if (band_xy.empty() || floor_xy.empty()) return;
  Eigen::Vector2d lo = band_xy[0], hi = band_xy[0];
  for (const auto* set : {&band_xy, &floor_xy})
    for (const auto& p : *set) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  OccupancyGrid grid;
  grid.resolution_m = s.floor_plan_cell_m;
  check_grid(hi - lo, grid.resolution_m, "the floor plan");
  grid.origin_m = lo;
  grid.width = static_cast<int>((hi.x() - lo.x()) / grid.resolution_m) + 1;
  grid.height = static_cast<int>((hi.y() - lo.y()) / grid.resolution_m) + 1;
  const auto tall = tall_cells(band_xy, band_z, zlo, zhi, lo, grid.resolution_m, grid.width, grid.height, 1, s);
  // Free: the floor seen (closed over a far floor's scan lines), nothing
  // standing on it up to a door's height.
  cv::Mat1b seen(grid.height, grid.width, uchar{0}), standing(grid.height, grid.width, uchar{0});
  for (const auto& p : cloud.points) {
    const Eigen::Vector2i c = grid.cell_of(p.head<2>().cast<double>());
    if (!grid.contains(c.x(), c.y())) continue;
    const double h = p.z() - floor.height_m;
    if (std::abs(h) < s.plane_band_m) seen(c.y(), c.x()) = 255;
    else if (h >= s.plane_band_m && h < s.door_min_height_m) standing(c.y(), c.x()) = 255;
  }
  cv::morphologyEx(seen, seen, cv::MORPH_CLOSE, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(5, 5)));
  grid.cells.assign(tall.size(), CellState::Unknown);
  for (int r = 0; r < grid.height; ++r)
    for (int c = 0; c < grid.width; ++c) {
      const std::size_t i = static_cast<std::size_t>(r) * static_cast<std::size_t>(grid.width) + static_cast<std::size_t>(c);
      grid.cells[i] = tall[i] ? CellState::Occupied : seen(r, c) && !standing(r, c) ? CellState::Free : CellState::Unknown;
    }
  if (std::none_of(grid.cells.begin(), grid.cells.end(), [](CellState v) { return v == CellState::Occupied; }) ||
      std::none_of(grid.cells.begin(), grid.cells.end(), [](CellState v) { return v == CellState::Free; }))
    return;
  FloorPlanSettings fs;
  fs.door_min_width_m = s.door_min_width_m;
  fs.door_max_width_m = s.door_max_width_m;
  fs.wall_height_m = zhi - floor.height_m;
  // Cupboards and shelves along a room's walls are tall too: the slab seen
  // in the band is the wall and them, wider than a 2D map's wall.
  fs.max_wall_thickness_m = 0.7;
  const Segmentation plan = segment_floor_plan(grid, fs);

  for (const Wall& pw : plan.walls) {
    Line2 line;
    line.point = pw.from_m;
    line.direction = pw.direction();
    line.normal = {-line.direction.y(), line.direction.x()};
    const double len = pw.length_m(), half = pw.thickness_m / 2 + s.wall_inlier_m;
    // The wall's stretches between the plan's doorways.
    std::vector<Run> runs;
    double from = 0;
    for (const auto& o : pw.openings) {
      runs.push_back({from, o.at_m});
      from = o.at_m + o.width_m;
    }
    runs.push_back({from, len});
    const Slab slab = slab_of(cloud, line, half, 0, len, runs, pw.both_faces_seen, floor.height_m, z_roof);
    Wall cur = pw;
    cur.height_m = slab.top_m;
    cur.openings.clear();
    double start = 0;  // cur's from_m along the plan's wall
    const auto close = [&](double end) {
      cur.from_m = line.point + line.direction * start;
      cur.to_m = line.point + line.direction * end;
      walls.push_back(cur);
    };
    for (const auto& o : pw.openings) {
      const double g0 = o.at_m, g1 = o.at_m + o.width_m;
      const GapReport rep = inspect_gap(slab.along_height, g0, g1, slab.top_m, slab.cell_m, s);
      const bool open = rep.free_below && !rep.panel && floor_through(line, half, g0, g1, floor_xy, s);
      const bool door = !rep.window && ((rep.lintel && (rep.panel || open)) || (rep.panel && !rep.lintel));
      Door d;
      d.center_m = line.point + line.direction * ((g0 + g1) / 2);
      d.yaw_rad = std::atan2(line.direction.y(), line.direction.x());
      d.width_m = g1 - g0;
      d.height_m = rep.lintel ? std::min(rep.lintel_bottom_m, slab.top_m) : rep.panel_top_m;
      d.wall_thickness_m = pw.thickness_m;
      d.lintel = rep.lintel;
      d.panel = rep.panel;
      if (door && rep.lintel) {
        cur.openings.push_back({g0 - start, g1 - g0, d.height_m});
        d.wall = static_cast<int>(walls.size());
        doors.push_back(d);
        continue;
      }
      // No wall above it: the gap lies between two walls.
      d.wall_before = static_cast<int>(walls.size());
      d.wall_after = d.wall_before + 1;
      close(g0);
      if (door) doors.push_back(d);
      cur.openings.clear();
      start = g1;
    }
    close(len);
  }
}

// The points find_walls_and_doors works from: the wall band's (between
// floor and ceiling) as xy and z, and the floor's as xy.
struct BandPoints {
  std::vector<Eigen::Vector2d> band_xy, floor_xy;
  std::vector<double> band_z;
};

BandPoints band_points(const Cloud& cloud, const SegmentationSettings& s, double floor_m, double zlo, double zhi) {
  BandPoints out;
  for (const auto& p : cloud.points) {
    if (p.z() >= zlo && p.z() <= zhi) {
      out.band_xy.push_back(p.head<2>().cast<double>());
      out.band_z.push_back(p.z());
    } else if (std::abs(p.z() - floor_m) < s.plane_band_m) {
      out.floor_xy.push_back(p.head<2>().cast<double>());
    }
  }
  // Floor points thinned: the side test needs their density, not each one.
  if (out.floor_xy.size() > 50000) {
    const std::size_t stride = out.floor_xy.size() / 50000 + 1;
    std::vector<Eigen::Vector2d> thin;
    for (std::size_t i = 0; i < out.floor_xy.size(); i += stride) thin.push_back(out.floor_xy[i]);
    out.floor_xy.swap(thin);
  }
  return out;
}

// A door found in a wall line's gap; its walls are known once the
// segments are snapped at the corners.
struct PendingDoor {
  Door door;
  std::size_t seg_before, seg_after;  // segment indices; SIZE_MAX: none
  bool in_wall;
};

// A wall line's slab as slab_of gathers it over the line's runs, and the
// along positions of its faces' points 0.3 to 1.5 m above the floor (where
// a gap's jambs are).
struct LineSlab {
  Slab slab;
  std::vector<double> face_low;
};

LineSlab line_slab(const Cloud& cloud, const WallLine& w, double half_m, double inlier_m, double z_floor, double z_roof) {
  LineSlab out;
  std::vector<double> heights;
  for (const auto& p : cloud.points) {
    if (p.z() > z_roof) continue;
    const Eigen::Vector2d xy = p.head<2>().cast<double>();
    if (std::abs(w.line.offset(xy)) > half_m) continue;
    const double a = w.line.along(xy);
    if (a < w.runs.front().first - 0.2 || a > w.runs.back().second + 0.2) continue;
    out.slab.along_height.push_back({a, p.z() - z_floor});
    const double h = p.z() - z_floor;
    if (h > 0.3 && h < 1.5 && std::abs(std::abs(w.line.offset(xy)) - w.thickness_m / 2) < inlier_m)
      out.face_low.push_back(a);
    for (const auto& r : w.runs)
      if (a >= r.first && a <= r.second) {
        heights.push_back(p.z() - z_floor);
        break;
      }
  }
  set_top_and_cell(out.slab, heights, w.runs, w.both);
  return out;
}

// A gap's sides (the jambs), from the points on the faces below any
// lintel, clear of a panel in the middle of the slab.
std::pair<double, double> jambs(const std::vector<double>& face_low, double g0, double g1) {
  const double mid = (g0 + g1) / 2;
  double a0 = g0, a1 = g1;
  std::vector<double> before, after;
  for (double a : face_low) {
    if (a >= g0 - 0.1 && a <= mid) before.push_back(a);
    if (a >= mid && a <= g1 + 0.1) after.push_back(a);
  }
  // Robust ends: the jamb's own points scatter by the range noise.
  if (before.size() >= 10) a0 = quantile(before, 0.97);
  if (after.size() >= 10) a1 = quantile(after, 0.03);
  return {a0, a1};
}

// Each wall line split at its gaps into segments; a gap of door width with
// wall above it or a panel in it is a door.
struct GapSplit {
  const Cloud& cloud;
  const SegmentationSettings& s;
  double z_floor, z_roof;
  const std::vector<Eigen::Vector2d>& floor_xy;
  std::vector<Segment> segs;
  std::vector<PendingDoor> pending;

  void split(const WallLine& w, std::size_t li) {
    const double half = w.thickness_m / 2 + s.wall_inlier_m;
    const LineSlab ls = line_slab(cloud, w, half, s.wall_inlier_m, z_floor, z_roof);
    const double top_m = ls.slab.top_m;
    Segment cur{li, w.runs.front().first, w.runs.front().second, {}, top_m, w.points};
    for (std::size_t k = 1; k <= w.runs.size(); ++k) {
      if (k == w.runs.size()) {
        segs.push_back(cur);
        break;
      }
      double g0 = w.runs[k - 1].second, g1 = w.runs[k].first;
      GapReport rep;
      if (g1 - g0 >= s.door_min_width_m - 0.15 && g1 - g0 <= s.door_max_width_m + 0.05) {
        std::tie(g0, g1) = jambs(ls.face_low, g0, g1);
        if (g1 - g0 >= s.door_min_width_m && g1 - g0 <= s.door_max_width_m)
          rep = inspect_gap(ls.slab.along_height, g0, g1, top_m, ls.slab.cell_m, s);
      }
      const double gap = g1 - g0;
      // The floor seen through a gap up to a doorway's width, on both sides
      // (a gap in a face shadowed by something in front of it has none beyond).
      const bool seen_through = gap <= s.door_max_width_m + 0.05 && floor_through(w.line, half, g0, g1, floor_xy, s);
      const bool open = rep.free_below && !rep.panel && seen_through;  // an open doorway
      const bool door = !rep.window && ((rep.lintel && (rep.panel || open)) || (rep.panel && !rep.lintel));
      if (door) {
        Door d;
        const Eigen::Vector2d c = w.line.point + w.line.direction * ((g0 + g1) / 2);
        d.center_m = c;
        d.yaw_rad = std::atan2(w.line.direction.y(), w.line.direction.x());
        d.width_m = gap;
        d.height_m = rep.lintel ? rep.lintel_bottom_m : rep.panel_top_m;
        d.wall_thickness_m = w.thickness_m;
        d.lintel = rep.lintel;
        d.panel = rep.panel;
        if (rep.lintel) {
          cur.openings.push_back({g0, gap, rep.lintel_bottom_m});
          cur.s1 = w.runs[k].second;
          pending.push_back({d, segs.size(), segs.size(), true});
          continue;
        }
        pending.push_back({d, segs.size(), segs.size() + 1, false});
        cur.s1 = g0;
        segs.push_back(cur);
        cur = Segment{li, g1, w.runs[k].second, {}, top_m, w.points};
        continue;
      }
      // A gap no wider than a doorway with no floor seen through it is wall
      // the sensor did not see (behind something, in its shadow): closed.
      if (gap <= s.door_max_width_m + 0.05 && !seen_through) {
        cur.s1 = w.runs[k].second;
        continue;
      }
      segs.push_back(cur);
      cur = Segment{li, w.runs[k].first, w.runs[k].second, {}, top_m, w.points};
    }
  }
};

// Corners: an end near another wall's centre line (both ends within
// corner_gap_m past the faces: a corner seen sparsely) is moved onto it; a
// free end is drawn in by half the thickness (the world file's walls are
// lengthened by that much past each end). Per segment, its ends along its line.
std::vector<std::pair<double, double>> snapped_ends(const std::vector<Segment>& segs, const std::vector<WallLine>& lines,
                                                    const SegmentationSettings& s) {
  std::vector<std::pair<double, double>> ends(segs.size());
  for (std::size_t i = 0; i < segs.size(); ++i) {
    const Line2& li = lines[segs[i].line].line;
    const double ti = lines[segs[i].line].thickness_m;
    double e[2] = {segs[i].s0, segs[i].s1};
    for (int side = 0; side < 2; ++side) {
      bool snapped = false;
      double best = std::numeric_limits<double>::infinity();
      for (std::size_t j = 0; j < segs.size(); ++j) {
        if (j == i) continue;
        const Line2& lj = lines[segs[j].line].line;
        const double tj = lines[segs[j].line].thickness_m;
        const double cross = li.direction.x() * lj.direction.y() - li.direction.y() * lj.direction.x();
        if (std::abs(cross) < std::sin(30.0 * M_PI / 180.0)) continue;
        // li.point + a·li.dir on lj: lj.offset = 0.
        const double a = -lj.offset(li.point) / lj.normal.dot(li.direction);
        const double here = side == 0 ? segs[i].s0 : segs[i].s1;
        const double reach = ti / 2 + tj / 2 + s.corner_gap_m;
        if (std::abs(a - here) > reach) continue;
        const double along_j = lj.along(li.point + li.direction * a);
        if (along_j < segs[j].s0 - reach || along_j > segs[j].s1 + reach) continue;
        if (std::abs(a - here) < best) {
          best = std::abs(a - here);
          e[side] = a;
          snapped = true;
        }
      }
      if (!snapped) e[side] += side == 0 ? ti / 2 : -ti / 2;
    }
    ends[i] = {e[0], e[1]};
  }
  return ends;
}

// The split's segments, snapped at the corners, as walls (those at least
// wall_min_length_m long) and its doors on them.
void add_walls_and_doors(const GapSplit& split, const std::vector<WallLine>& lines, const SegmentationSettings& s,
                         std::vector<Wall>& walls, std::vector<Door>& doors) {
  const auto& segs = split.segs;
  const auto ends = snapped_ends(segs, lines, s);
  const auto end_point = [&](const Segment& g, double a) { return lines[g.line].line.point + lines[g.line].line.direction * a; };
  std::vector<int> index(segs.size(), -1);
  for (std::size_t i = 0; i < segs.size(); ++i) {
    const auto [a0, a1] = ends[i];
    if (a1 - a0 < s.wall_min_length_m) continue;
    Wall w;
    w.from_m = end_point(segs[i], a0);
    w.to_m = end_point(segs[i], a1);
    w.height_m = segs[i].height_m;
    w.thickness_m = lines[segs[i].line].thickness_m;
    w.both_faces_seen = lines[segs[i].line].both;
    w.points = segs[i].points;
    for (auto o : segs[i].openings) {
      o.at_m -= a0;
      o.height_m = std::min(o.height_m, w.height_m);
      if (o.at_m >= 0 && o.at_m + o.width_m <= a1 - a0) w.openings.push_back(o);
    }
    index[i] = static_cast<int>(walls.size());
    walls.push_back(w);
  }
  for (const auto& p : split.pending) {
    Door d = p.door;
    if (p.in_wall) {
      d.wall = p.seg_before < segs.size() ? index[p.seg_before] : -1;
      if (d.wall < 0) continue;
    } else {
      d.wall_before = p.seg_before < segs.size() ? index[p.seg_before] : -1;
      d.wall_after = p.seg_after < segs.size() ? index[p.seg_after] : -1;
    }
    doors.push_back(d);
  }
}
}  // namespace

void find_walls_and_doors(const Cloud& cloud, const SegmentationSettings& s, const Floor& floor,
                          const Ceiling& ceiling, std::vector<Wall>& walls, std::vector<Door>& doors) {
  const double zlo = floor.height_m + s.wall_band_margin_m;
  double zhi = floor.height_m + s.wall_band_top_m;
  if (ceiling.found) zhi = std::min(zhi, ceiling.height_m - s.wall_band_margin_m);
  const double z_roof = ceiling.found ? ceiling.height_m - 0.04 : std::numeric_limits<double>::infinity();
  const BandPoints band = band_points(cloud, s, floor.height_m, zlo, zhi);
  if (s.walls_from_floor_plan) {
    walls_from_floor_plan(cloud, s, floor, zlo, zhi, z_roof, band.band_xy, band.band_z, band.floor_xy, walls, doors);
    return;
  }
  const auto faces = find_faces(band.band_xy, band.band_z, zlo, zhi, s);
  const auto lines = build_wall_lines(faces, band.floor_xy, s);
  GapSplit split{cloud, s, floor.height_m, z_roof, band.floor_xy, {}, {}};
  for (std::size_t li = 0; li < lines.size(); ++li) split.split(lines[li], li);
  add_walls_and_doors(split, lines, s, walls, doors);
}

}  // namespace rise::semantic::detail
