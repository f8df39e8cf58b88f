#include "semantic/icp.hpp"

#include <omp.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <bit>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <stdexcept>

#include "semantic/voxel_grid.hpp"

namespace rise::semantic {
namespace {

double huber_weight(double residual, double huber_m) {
  const double a = std::abs(residual);
  return (huber_m > 0.0 && a > huber_m) ? huber_m / a : 1.0;
}

// Per-thread sums of one iteration. Point-to-point keeps the moments of the
// weighted pairs (Horn/Umeyama closed form); point-to-plane the normal
// equations JᵀWJ δ = -JᵀWr of the linearised residual n·(p' + ω×p' + v - q).
struct Sums {
  Eigen::Matrix<double, 6, 6> JtJ = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> Jtr = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix3d Spq = Eigen::Matrix3d::Zero();  // Σ w p' qᵀ
  Eigen::Vector3d Sp = Eigen::Vector3d::Zero();   // Σ w p'
  Eigen::Vector3d Sq = Eigen::Vector3d::Zero();   // Σ w q
  double Sw = 0.0;
  double squared_error = 0.0;  // Σ d², unweighted, for the rmse
  size_t pairs = 0;
  size_t points = 0;  // source points this iteration used

  void add(const Sums& o) {
    JtJ += o.JtJ;
    Jtr += o.Jtr;
    Spq += o.Spq;
    Sp += o.Sp;
    Sq += o.Sq;
    Sw += o.Sw;
    squared_error += o.squared_error;
    pairs += o.pairs;
    points += o.points;
  }

  /// A point-to-plane pair: residual r = n·(p' - q), Jacobian row [p' × n, n].
  void add_plane_pair(const Eigen::Vector3d& pd, const Eigen::Vector3d& qd, const Eigen::Vector3d& nd, double huber_m) {
    const double r = nd.dot(pd - qd);
    const double w = huber_weight(r, huber_m);
    Eigen::Matrix<double, 6, 1> J;
    J.head<3>() = pd.cross(nd);
    J.tail<3>() = nd;
    JtJ.selfadjointView<Eigen::Upper>().rankUpdate(J, w);
    Jtr += (w * r) * J;
  }
  /// A point-to-point pair `distance2_m2` apart: its weighted moments.
  void add_point_pair(const Eigen::Vector3d& pd, const Eigen::Vector3d& qd, float distance2_m2, double huber_m) {
    const double w = huber_weight(std::sqrt(static_cast<double>(distance2_m2)), huber_m);
    Sw += w;
    Sp += w * pd;
    Sq += w * qd;
    Spq += (w * pd) * qd.transpose();
  }
};

// The rigid motion that best maps the weighted p' onto q (Umeyama 1991,
// eq. 39-41 without scale), from the accumulated moments.
Eigen::Isometry3d closed_form(const Sums& s) {
  const Eigen::Vector3d mp = s.Sp / s.Sw, mq = s.Sq / s.Sw;
  const Eigen::Matrix3d H = s.Spq - s.Sw * mp * mq.transpose();  // Σ w (p'-mp)(q-mq)ᵀ
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  if ((svd.matrixV() * svd.matrixU().transpose()).determinant() < 0.0) D(2, 2) = -1.0;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = svd.matrixV() * D * svd.matrixU().transpose();
  T.translation() = mq - T.linear() * mp;
  return T;
}

Eigen::Isometry3d gauss_newton(const Sums& s) {
  const Eigen::Matrix<double, 6, 1> delta = s.JtJ.ldlt().solve(-s.Jtr);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d w = delta.head<3>();
  if (!delta.allFinite()) return T;
  const double angle = w.norm();
  if (angle > 0.0) T.linear() = Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
  T.translation() = delta.tail<3>();
  return T;
}

}  // namespace

namespace detail {

// Nearest neighbours at any radius up to the first iteration's: grids whose
// cells are twice a radius that halves level by level, down to about the
// point spacing. A query starts at the level its point needed last iteration
// (the finest at first; 8 cells, exact within the level's radius) and climbs
// only while it finds nothing, so a converged pair
// costs one small lookup however large the first radius was. Every level but
// the finest reads a bounded, evenly spread sample of a crowded cell: a far
// point's partner only has to point the right way, and pairs within the
// finest radius stay exact. With exact_neighbours, only searches wider than
// the minimum pairing distance sample: every pair the last iterations use
// is then the exact nearest neighbour, as a k-d tree would give.
class GridPyramid {
 public:
  GridPyramid(const std::vector<Eigen::Vector3f>& points, double max_radius_m, double exact_radius_m,
              bool exact, int max_points_per_cell)
      : exact_(exact) {
    constexpr int kMaxLevels = 8;
    std::vector<float> radii{static_cast<float>(max_radius_m)};
    auto top = std::make_unique<VoxelGrid>(points, 2.0f * radii[0], max_points_per_cell);
    // A surface's points per cell grow with the cell's area: spacing ~ cell / sqrt(points per cell).
    // The median over points of their cell's count: what a typical query sees.
    std::vector<uint32_t> counts;
    const auto& offsets = top->cell_offsets();
    for (size_t c = 0; c + 1 < offsets.size(); ++c) counts.push_back(offsets[c + 1] - offsets[c]);
    std::sort(counts.begin(), counts.end());
    double per_cell = 1.0;
    for (size_t c = 0, seen = 0; c < counts.size(); ++c)
      if ((seen += counts[c]) * 2 >= top->size()) {
        per_cell = counts[c];
        break;
      }
    const double spacing_m = 2.0 * max_radius_m / std::sqrt(std::max(1.0, per_cell));
    while (static_cast<int>(radii.size()) < kMaxLevels && radii.back() * 0.5 >= spacing_m)
      radii.push_back(radii.back() * 0.5f);
    exact_radius_m_ = static_cast<float>(exact_radius_m * (1.0 + 1e-6));
    const auto cap = [&](size_t l) { return l + 1 == radii.size() ? 0u : kStrideCap; };
    for (size_t l = radii.size(); l-- > 1;)
      levels_.push_back({std::make_unique<VoxelGrid>(points, 2.0f * radii[l], max_points_per_cell), radii[l], cap(l)});
    levels_.push_back({std::move(top), radii[0], cap(0)});
  }

  /// `level` in: where to start; out: the finest level whose radius holds
  /// the answer, where the next iteration (pairs change little) should
  /// start. Starting higher finds the same point, at more cost: what a
  /// level finds is the nearest within its whole radius.
  /// With `clear_m` non-null, also the clearance of the answer
  /// (VoxelGrid::nearest_with_clearance) when the search that gave it read
  /// every point in its radius, else 0: with nothing found, no point lies
  /// within the clearance.
  VoxelGrid::Neighbour nearest(const Eigen::Vector3f& q, float radius_m, uint8_t& level, uint8_t widest,
                               float* clear_m = nullptr) const {
    if (clear_m != nullptr) *clear_m = 0.0f;
    for (size_t l = std::min<size_t>(level, widest); l < levels_.size(); ++l) {
      const Level& lv = levels_[l];
      const float r = std::min(lv.radius_m, radius_m);
      const bool sample = !exact_ || r > exact_radius_m_;
      const uint32_t stride = sample ? lv.stride_cap : 0u;
      VoxelGrid::Neighbour nb;
      float clear = 0.0f;
      if (clear_m != nullptr && stride == 0) {
        nb = lv.grid->nearest_with_clearance(q, r, clear);
      } else {
        nb = lv.grid->nearest(q, r, stride);
      }
      if (nb.index != VoxelGrid::kNone) {
        level = level_of(nb.distance2_m2);
        if (clear_m != nullptr) *clear_m = clear;
        return nb;
      }
      if (r >= radius_m || l + 1 == levels_.size()) {
        if (clear_m != nullptr) *clear_m = clear;
        break;
      }
    }
    level = static_cast<uint8_t>(levels_.size() - 1);
    return {};
  }
  /// The finest level whose radius holds a pair `distance2_m2` apart:
  /// where the next search for it starts.
  uint8_t level_of(float distance2_m2) const {
    size_t m = 0;
    while (m + 1 < levels_.size() && levels_[m].radius_m * levels_[m].radius_m < distance2_m2) ++m;
    return static_cast<uint8_t>(m);
  }
  uint8_t coarsest() const { return static_cast<uint8_t>(levels_.size() - 1); }
  /// The finest level whose radius covers `radius_m`: no search at that
  /// radius needs to start above it.
  uint8_t level_for(float radius_m) const {
    size_t l = 0;
    while (l + 1 < levels_.size() && levels_[l].radius_m < radius_m) ++l;
    return static_cast<uint8_t>(l);
  }

 private:
  static constexpr uint32_t kStrideCap = 32;
  struct Level {
    std::unique_ptr<VoxelGrid> grid;
    float radius_m;
    uint32_t stride_cap;
  };
  std::vector<Level> levels_;  // finest first
  float exact_radius_m_ = 0.0f;  // exact_: searches up to this radius read every point
  bool exact_ = false;
};

}  // namespace detail

namespace {

using detail::GridPyramid;

// A cell size that puts about k / 2 points in a cell of a surface, so that
// the k nearest usually lie within the 3x3x3 block around a point's cell
// (k_nearest then reads no second ring): start from the bounding box, then
// correct for the mean occupancy (a surface's points per cell grow with
// the square of the size). 0 when no point is finite.
float normals_cell_m(const std::vector<Eigen::Vector3f>& points, int k) {
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
  Eigen::Vector3f hi = -lo;
  size_t finite = 0;
  for (const auto& p : points)
    if (p.allFinite()) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
      ++finite;
    }
  if (finite == 0) return 0.0f;
  const Eigen::Vector3f extent = (hi - lo).cwiseMax(1e-3f);
  float cell = std::cbrt(extent.prod() / static_cast<float>(finite)) * 2.0f;
  if (!(cell > 1e-4f) || !std::isfinite(cell)) cell = 1e-2f;
  const float per_cell = static_cast<float>(finite) / static_cast<float>(VoxelGrid::count_cells(points, cell));
  const float wanted = static_cast<float>(k) / 2.0f;
  if (per_cell > wanted) cell *= std::sqrt(wanted / per_cell);
  return cell;
}

// Both normal estimators' start: every normal +z, k checked, and the grid
// of cells of about k / 2 points (none when no point is finite).
std::optional<VoxelGrid> normals_grid(Cloud& cloud, int k, const char* who) {
  cloud.normals.assign(cloud.points.size(), Eigen::Vector3f::UnitZ());
  if (cloud.points.empty()) return std::nullopt;
  if (k < 3) throw std::invalid_argument(std::string(who) + ": k must be at least 3");
  const float cell = normals_cell_m(cloud.points, k);
  if (cell == 0.0f) return std::nullopt;
  return VoxelGrid(cloud.points, cell);
}

// The target and the settings; validate() adds the source.
void validate_target(const Cloud& target, const IcpSettings& s) {
  if (target.empty()) throw std::invalid_argument("icp: target cloud is empty");
  if (s.metric == IcpMetric::PointToPlane && target.normals.size() != target.points.size())
    throw std::invalid_argument("icp: point-to-plane needs one normal per target point (estimate_normals)");
  if (s.max_iterations < 1) throw std::invalid_argument("icp: max_iterations must be at least 1");
  if (!(s.min_correspondence_m > 0.0) || !(s.max_correspondence_m >= s.min_correspondence_m) ||
      !std::isfinite(s.max_correspondence_m))
    throw std::invalid_argument("icp: need 0 < min_correspondence_m <= max_correspondence_m");
  if (!(s.huber_m >= 0.0)) throw std::invalid_argument("icp: huber_m must be >= 0");
  if (s.threads < 0) throw std::invalid_argument("icp: threads must be >= 0");
  if (s.max_points_per_cell < 0) throw std::invalid_argument("icp: max_points_per_cell must be >= 0");
  if (s.coarse_stride < 1) throw std::invalid_argument("icp: coarse_stride must be at least 1");
}

void validate(const Cloud& source, const Cloud& target, const IcpSettings& s) {
  if (source.empty()) throw std::invalid_argument("icp: source cloud is empty");
  validate_target(target, s);
}

// The stride of iteration `it`: coarse_stride over the first half, then
// halving in equal steps down to 1 for the last ones. Each chunk counts
// its stride from its own first point: the points used depend on the
// chunks only, not on the threads.
std::ptrdiff_t stride_of(const IcpSettings& s, int it) {
  const int coarse_iterations = s.max_iterations / 2;
  if (it < coarse_iterations) return s.coarse_stride;
  const int halvings = std::bit_width(static_cast<unsigned>(s.coarse_stride)) - 1;  // log2, rounded down
  const int rest = s.max_iterations - coarse_iterations;
  const int step = (it - coarse_iterations) * (halvings + 1) / std::max(1, rest);  // 0 .. halvings
  return std::max<std::ptrdiff_t>(1, s.coarse_stride >> (step + 1));
}

// One iteration's pass over the source: each (strided) source point, moved
// by the current pose, paired with its nearest target point within the
// iteration's radius, and the pairs' terms summed. Work in fixed chunks
// handed out dynamically (a thread the OS parks on a busy machine does not
// hold up the others), each summed into its own slot and the slots added in
// order: the same answer for any number of threads and any schedule. What
// the passes carry from one iteration to the next is allocated once, here.
class PairPass {
 public:
  PairPass(const Cloud& source, const Cloud& target, const IcpSettings& s, int threads)
      : src_(source.points),
        target_(target),
        plane_(s.metric == IcpMetric::PointToPlane),
        reuse_(s.reuse_pairs && s.max_points_per_cell == 0),
        huber_m_(s.huber_m),
        threads_(threads),
        chunks_((static_cast<std::ptrdiff_t>(src_.size()) + kChunk - 1) / kChunk),
        partial_(static_cast<size_t>(chunks_)),
        hint_(src_.size(), 0),
        memo_(reuse_ ? src_.size() : 0) {}

  Sums sum_pairs(const GridPyramid& pyramid, const Eigen::Isometry3d& T, double radius, std::ptrdiff_t stride) {
    const auto& src = src_;
    const auto& target = target_;
    const auto& tn = target.normals;
    auto& hint = hint_;
    auto& memo = memo_;
    auto& partial = partial_;
    const bool plane = plane_, reuse = reuse_;
    const double huber = huber_m_;
    const auto n = static_cast<std::ptrdiff_t>(src.size());
    const std::ptrdiff_t chunks = chunks_;
    const float rf = static_cast<float>(radius);
    const uint8_t widest = pyramid.level_for(rf);
    const Eigen::Matrix3f R = T.linear().cast<float>();
    const Eigen::Vector3f t = T.translation().cast<float>();
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads_)
    for (std::ptrdiff_t c = 0; c < chunks; ++c) {
      Sums acc;  // a local: the compiler keeps it in registers, and threads share no cache line
      for (std::ptrdiff_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); i += stride) {
        ++acc.points;
        const Eigen::Vector3f p = R * src[static_cast<size_t>(i)] + t;
        uint8_t& level = hint[static_cast<size_t>(i)];
        const VoxelGrid::Neighbour nb = reuse ? nearest_reusing(pyramid, p, rf, widest, level, memo[static_cast<size_t>(i)])
                                              : pyramid.nearest(p, rf, level, widest);
        if (nb.index == VoxelGrid::kNone) continue;
        const Eigen::Vector3d pd = p.cast<double>();
        const Eigen::Vector3d qd = target.points[nb.index].cast<double>();
        acc.squared_error += nb.distance2_m2;
        ++acc.pairs;
        if (plane) {
          acc.add_plane_pair(pd, qd, tn[nb.index].cast<double>(), huber);
        } else {
          acc.add_point_pair(pd, qd, nb.distance2_m2, huber);
        }
      }
      partial[static_cast<size_t>(c)] = acc;
    }
    Sums s;
    for (const auto& p : partial) s.add(p);
    return s;
  }

 private:
  // Per source point, its last exact search: where it was, its answer and
  // that answer's clearance (0: none to reuse). Capped cells keep different
  // points per level: no reuse there.
  struct Memo {
    Eigen::Vector3f at = Eigen::Vector3f::Zero();
    float clear_m = 0.0f;
    uint32_t index = VoxelGrid::kNone;
  };

  // Moved by δ since its last exact search: every other target point is
  // still at least clear − δ away, so while its answer is nearer than that
  // it is still the nearest, and a search would return it (with the same
  // start level). The same pairs, without the search.
  VoxelGrid::Neighbour nearest_reusing(const GridPyramid& pyramid, const Eigen::Vector3f& p, float rf, uint8_t widest,
                                       uint8_t& level, Memo& m) const {
    const float delta = (p - m.at).norm();
    const float slack = delta + 1e-6f * (p.cwiseAbs().maxCoeff() + 1.0f);  // float rounding
    if (m.clear_m > 0.0f) {
      if (m.index != VoxelGrid::kNone) {
        const Eigen::Vector3f& tp = target_.points[m.index];
        const float d2 = (Eigen::Vector4f(tp.x(), tp.y(), tp.z(), 0.0f) - Eigen::Vector4f(p.x(), p.y(), p.z(), 0.0f)).squaredNorm();
        if (std::sqrt(d2) + slack < m.clear_m) {
          if (d2 <= rf * rf) {
            level = pyramid.level_of(d2);
            return {m.index, d2};
          }
          level = pyramid.coarsest();
          return {};
        }
      } else if (rf + slack < m.clear_m) {
        level = pyramid.coarsest();  // nothing within the clearance then: nothing within rf now
        return {};
      }
    }
    float clear = 0.0f;
    const VoxelGrid::Neighbour nb = pyramid.nearest(p, rf, level, widest, &clear);
    m = {p, clear, nb.index};
    return nb;
  }

  static constexpr std::ptrdiff_t kChunk = 1024;
  const std::vector<Eigen::Vector3f>& src_;
  const Cloud& target_;
  const bool plane_, reuse_;
  const double huber_m_;
  const int threads_;
  const std::ptrdiff_t chunks_;
  std::vector<Sums> partial_;
  std::vector<uint8_t> hint_;  // per source point: the pyramid level to start at
  std::vector<Memo> memo_;     // per source point, with reuse
};

// The motion this iteration's sums ask for: a Gauss-Newton step
// (point-to-plane) or the closed form (point-to-point).
Eigen::Isometry3d step_from(Sums& s, bool plane) {
  if (!plane) return closed_form(s);
  s.JtJ = s.JtJ.selfadjointView<Eigen::Upper>();
  return gauss_newton(s);
}

}  // namespace

std::vector<double> correspondence_schedule(const IcpSettings& s) {
  // Geometric from max to min over the first half of the iterations (the
  // paper's GPU ICP narrows its search each iteration), then min.
  const int shrink = std::max(1, s.max_iterations / 2);
  const double ratio = s.min_correspondence_m / s.max_correspondence_m;
  std::vector<double> r(static_cast<size_t>(s.max_iterations), s.min_correspondence_m);
  for (int i = 0; i < std::min(shrink, s.max_iterations); ++i)
    r[static_cast<size_t>(i)] = s.max_correspondence_m * std::pow(ratio, static_cast<double>(i) / shrink);
  return r;
}

IcpTarget::IcpTarget(const Cloud& target, const IcpSettings& settings) : cloud_(target), settings_(settings) {
  validate_target(target, settings);
  pyramid_ = std::make_unique<GridPyramid>(target.points, correspondence_schedule(settings).front(),
                                           settings.min_correspondence_m, settings.exact_neighbours,
                                           settings.max_points_per_cell);
}

IcpTarget::~IcpTarget() = default;

IcpResult icp(const Cloud& source, const Cloud& target, const Eigen::Isometry3d& T_initial,
              const IcpSettings& settings) {
  validate(source, target, settings);
  return icp(source, IcpTarget(target, settings), T_initial);
}

IcpResult icp(const Cloud& source, const IcpTarget& prepared, const Eigen::Isometry3d& T_initial) {
  return icp(source, prepared, T_initial, {});
}

IcpResult icp(const Cloud& source, const IcpTarget& prepared, const Eigen::Isometry3d& T_initial,
              const std::function<bool(const Eigen::Isometry3d&, const IcpResult&)>& stop) {
  const IcpSettings& settings = prepared.settings();
  const Cloud& target = prepared.cloud();
  validate(source, target, settings);
  const auto schedule = correspondence_schedule(settings);
  const bool plane = settings.metric == IcpMetric::PointToPlane;
  // A thread per 512 source points at most: below that, waking threads costs more than it saves.
  const int useful = static_cast<int>(std::min<size_t>(1024, source.points.size() / 512 + 1));
  const int threads = std::min(useful, settings.threads > 0 ? settings.threads : omp_get_max_threads());

  const GridPyramid& pyramid = *prepared.pyramid_;
  PairPass pass(source, target, settings, threads);

  IcpResult result;
  Eigen::Isometry3d T = T_initial;
  for (int it = 0; it < settings.max_iterations; ++it) {
    const double radius = schedule[static_cast<size_t>(it)];
    const std::ptrdiff_t stride = stride_of(settings, it);
    Sums s = pass.sum_pairs(pyramid, T, radius, stride);
    result.iterations = it + 1;
    result.inlier_ratio = static_cast<double>(s.pairs) / static_cast<double>(s.points);
    result.rmse_m = s.pairs > 0 ? std::sqrt(s.squared_error / static_cast<double>(s.pairs)) : 0.0;
    const size_t needed = plane ? 6 : 3;
    if (s.pairs < needed) break;  // too few pairs to pin the pose down: keep the last one

    const Eigen::Isometry3d dT = step_from(s, plane);
    T = dT * T;
    const double moved = dT.translation().norm();
    const double turned = Eigen::AngleAxisd(dT.linear()).angle();
    result.last_step_m = moved;
    result.last_step_rad = turned;
    if (moved < settings.translation_epsilon_m && turned < settings.rotation_epsilon_rad &&
        radius <= settings.min_correspondence_m * (1.0 + 1e-9) && stride == 1) {
      result.converged = true;
      break;
    }
    if (stop && stop(T, result)) {
      result.stopped = true;
      break;
    }
  }
  T.linear() = Eigen::Quaterniond(T.linear()).normalized().toRotationMatrix();
  result.T_target_source = T;
  return result;
}

void estimate_normals(Cloud& cloud, int k, const Eigen::Vector3f& viewpoint, int threads) {
  const std::optional<VoxelGrid> made = normals_grid(cloud, k, "estimate_normals");
  if (!made) return;
  const VoxelGrid& grid = *made;
  const size_t n = cloud.points.size();

#pragma omp parallel num_threads(threads > 0 ? threads : omp_get_max_threads())
  {
    std::vector<VoxelGrid::Neighbour> nbs;
#pragma omp for schedule(dynamic, 256)
    for (std::ptrdiff_t i = 0; i < static_cast<std::ptrdiff_t>(n); ++i) {
      const Eigen::Vector3f& p = cloud.points[static_cast<size_t>(i)];
      grid.k_nearest(p, k, nbs);
      if (nbs.size() < 3) continue;
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (const auto& nb : nbs) mean += cloud.points[nb.index].cast<double>();
      mean /= static_cast<double>(nbs.size());
      Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
      for (const auto& nb : nbs) {
        const Eigen::Vector3d d = cloud.points[nb.index].cast<double>() - mean;
        C += d * d.transpose();
      }
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
      es.computeDirect(C);  // closed form for 3x3: a fraction of the iterative solver's cost
      Eigen::Vector3f normal = es.eigenvectors().col(0).cast<float>();  // smallest eigenvalue
      if (normal.dot(viewpoint - p) < 0.0f) normal = -normal;
      cloud.normals[static_cast<size_t>(i)] = normal;
    }
  }
}

void estimate_normals_cells(Cloud& cloud, int k, const Eigen::Vector3f& viewpoint, int threads) {
  const std::optional<VoxelGrid> made = normals_grid(cloud, k, "estimate_normals_cells");
  if (!made) return;
  const VoxelGrid& grid = *made;
  // Each cell's count, sum and sum of outer products (xx xy xz yy yz zz),
  // about one origin: doubles then keep a centimetre's spread exact in a
  // scene of a hundred metres.
  struct Moments {
    double n = 0.0;
    Eigen::Vector3d s = Eigen::Vector3d::Zero();
    Eigen::Matrix<double, 6, 1> m = Eigen::Matrix<double, 6, 1>::Zero();
  };
  const auto& pts = grid.grid_points();
  const auto& idx = grid.grid_index();
  const auto& offsets = grid.cell_offsets();
  const size_t cells = offsets.size() - 1;
  const Eigen::Vector3d origin = pts.front().head<3>().cast<double>();
  std::vector<Moments> moments(cells);
  std::vector<uint32_t> cell_at(pts.size(), 0);  // a cell's first point -> the cell
  for (size_t c = 0; c < cells; ++c) {
    cell_at[offsets[c]] = static_cast<uint32_t>(c);
    Moments& mo = moments[c];
    for (uint32_t j = offsets[c]; j < offsets[c + 1]; ++j) {
      const Eigen::Vector3d d = pts[j].head<3>().cast<double>() - origin;
      mo.n += 1.0;
      mo.s += d;
      mo.m += (Eigen::Matrix<double, 6, 1>() << d.x() * d.x(), d.x() * d.y(), d.x() * d.z(), d.y() * d.y(),
               d.y() * d.z(), d.z() * d.z()).finished();
    }
  }
  // One normal per cell, from its 3x3x3 block's summed moments, for all its points.
#pragma omp parallel for schedule(dynamic, 256) num_threads(threads > 0 ? threads : omp_get_max_threads())
  for (std::ptrdiff_t ci = 0; ci < static_cast<std::ptrdiff_t>(cells); ++ci) {
    const size_t c = static_cast<size_t>(ci);
    const Eigen::Vector3f first = pts[offsets[c]].head<3>();
    const Eigen::Vector3i at = grid.cell_coords(first);
    Moments sum;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const VoxelGrid::Run run = grid.run_at(at + Eigen::Vector3i(dx, dy, dz));
          if (run.count == 0) continue;
          const Moments& mo = moments[cell_at[run.begin]];
          sum.n += mo.n;
          sum.s += mo.s;
          sum.m += mo.m;
        }
    if (sum.n < 3.0) continue;
    const Eigen::Vector3d mean = sum.s / sum.n;
    Eigen::Matrix3d C;
    C << sum.m[0], sum.m[1], sum.m[2], sum.m[1], sum.m[3], sum.m[4], sum.m[2], sum.m[4], sum.m[5];
    C = C / sum.n - mean * mean.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
    es.computeDirect(C);
    const Eigen::Vector3f normal = es.eigenvectors().col(0).cast<float>();
    if (!normal.allFinite()) continue;
    for (uint32_t j = offsets[c]; j < offsets[c + 1]; ++j) {
      const Eigen::Vector3f p = pts[j].head<3>();
      cloud.normals[idx[j]] = normal.dot(viewpoint - p) < 0.0f ? Eigen::Vector3f(-normal) : normal;
    }
  }
}

Cloud voxel_filter(const Cloud& cloud, double leaf_m) {
  if (!(leaf_m > 0.0) || !std::isfinite(leaf_m)) throw std::invalid_argument("voxel_filter: leaf_m must be > 0");
  // Each cell's points summed in their order, the cells in the order the
  // points first reach them (a VoxelGrid's order, without building one).
  size_t cells = 0;
  const std::vector<uint32_t> cell = VoxelGrid::cell_numbers(cloud.points, static_cast<float>(leaf_m), cells);
  const bool normals = cloud.normals.size() == cloud.points.size();
  std::vector<Eigen::Vector3d> sum(cells, Eigen::Vector3d::Zero()), nsum(normals ? cells : 0, Eigen::Vector3d::Zero());
  std::vector<uint32_t> count(cells, 0);
  for (size_t i = 0; i < cell.size(); ++i) {
    const uint32_t c = cell[i];
    if (c == VoxelGrid::kNone) continue;
    sum[c] += cloud.points[i].cast<double>();
    ++count[c];
    if (normals) nsum[c] += cloud.normals[i].cast<double>();
  }
  Cloud out;
  out.points.reserve(cells);
  for (size_t c = 0; c < cells; ++c) {
    out.points.push_back((sum[c] / static_cast<double>(count[c])).cast<float>());
    if (normals) {
      const double len = nsum[c].norm();
      out.normals.push_back(len > 0.0 ? Eigen::Vector3f((nsum[c] / len).cast<float>()) : Eigen::Vector3f::UnitZ());
    }
  }
  return out;
}

}  // namespace rise::semantic
