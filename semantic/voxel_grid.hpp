#pragma once

// The seed paper's bucket structure for nearest-neighbour search: a regular
// grid of cubes of side `cell_m`, hashed (only occupied cells cost memory),
// each cell a contiguous run of its points. Built once, then read-only and
// safe to query from many threads. The idea follows KISS-ICP's and
// small_gicp's voxel hash maps; the layout is our own: the points are
// re-ordered cell by cell into one array (CSR), and an open-addressing table
// maps a cell's packed integer coordinates to its run.

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace rise::semantic {

class VoxelGrid {
 public:
  static constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

  struct Neighbour {
    uint32_t index = kNone;  ///< into the points the grid was built from; kNone: none found
    float distance2_m2 = std::numeric_limits<float>::infinity();
  };

  /// Buckets `points` (non-finite points are left out) into cubes of
  /// `cell_m` > 0. `max_points_per_cell` > 0 keeps only that many points
  /// of each cell (the first ones in input order): KISS-ICP's fixed-size
  /// cell lists, which bound a query's cost. Throws std::invalid_argument
  /// when cell_m is not positive and finite.
  VoxelGrid(const std::vector<Eigen::Vector3f>& points, float cell_m, int max_points_per_cell = 0);

  /// How many cubes of `cell_m` > 0 the finite points occupy: what
  /// VoxelGrid(points, cell_m).occupied_cells() says, without building the
  /// grid (a hash set of the cells' keys; a fraction of the cost). Counting
  /// stops past `limit` (returning limit + 1, and in `read` how many
  /// points it had read then): a search that only asks "more than this
  /// many, and about how many?" keeps a table of its own size, in cache.
  static size_t count_cells(const std::vector<Eigen::Vector3f>& points, float cell_m,
                            size_t limit = std::numeric_limits<size_t>::max() - 1, size_t* read = nullptr);

  /// Each point's cube of `cell_m` > 0 as a number in the order the points
  /// first reach the cubes (kNone for a point that is not finite), and in
  /// `cells` how many: the cells of VoxelGrid(points, cell_m), in its
  /// order, without its runs (the constructor's one pass over a hash
  /// table; for what only sums over each cell's points, voxel_filter).
  static std::vector<uint32_t> cell_numbers(const std::vector<Eigen::Vector3f>& points, float cell_m, size_t& cells);

  float cell_m() const { return cell_m_; }
  size_t occupied_cells() const { return cell_count_; }
  size_t size() const { return index_.size(); }  ///< points kept

  /// The nearest kept point within `radius_m` of `q` (exact while
  /// radius_m <= cell_m / 2: then at most 8 cells are read). No
  /// allocation, no throw: safe in a parallel loop.
  /// With `stride_cap` > 0, a cell of more points reads only about that
  /// many of them, evenly spread (an approximate answer at a bounded cost).
  Neighbour nearest(const Eigen::Vector3f& q, float radius_m, uint32_t stride_cap = 0) const {
    return search<false>(q, radius_m, stride_cap, nullptr);
  }

  /// nearest() reading every point, and also `clear_m`: no kept point
  /// other than the answer lies closer than that to q (the second nearest
  /// read, the nearest face of a cell skipped, or radius_m). A query that
  /// moves by δ keeps the same answer while its distance to it + δ stays
  /// below clear_m − δ (what ICP uses to skip searches exactly).
  Neighbour nearest_with_clearance(const Eigen::Vector3f& q, float radius_m, float& clear_m) const {
    float clear2 = 0.0f;
    const Neighbour nb = search<true>(q, radius_m, 0, &clear2);
    clear_m = std::sqrt(clear2);
    return nb;
  }

  /// The k nearest kept points to `q`, nearest first, into `out` (cleared
  /// first). Exact where the k-th lies within `max_rings` cells of q's
  /// cell; fewer than k when fewer lie that close.
  void k_nearest(const Eigen::Vector3f& q, int k, std::vector<Neighbour>& out, int max_rings = 3) const;

  /// q's distance to the nearest face of its own cell (a little less, for
  /// float rounding; 0 outside the grid's range).
  float face_gap(const Eigen::Vector3f& q) const;

  /// The integer coordinates of the cell holding q, and the points of the
  /// cell at such coordinates: grid_points()[begin, begin + count), count 0
  /// where no point lies.
  Eigen::Vector3i cell_coords(const Eigen::Vector3f& q) const { return {coord(q.x()), coord(q.y()), coord(q.z())}; }
  struct Run {
    uint32_t begin = 0, count = 0;
  };
  Run run_at(const Eigen::Vector3i& cell) const {
    for (int a = 0; a < 3; ++a)
      if (cell[a] > kCoordLimit || cell[a] < -kCoordLimit) return {};
    const Slot* s = find(pack(cell.x(), cell.y(), cell.z()));
    return s == nullptr ? Run{} : Run{s->begin, s->count};
  }

  /// Points in grid order (x y z), and the index of each into the input.
  const std::vector<Eigen::Vector4f>& grid_points() const { return sorted_; }
  const std::vector<uint32_t>& grid_index() const { return index_; }
  /// Cell c holds grid_points()[cell_offsets()[c] .. cell_offsets()[c + 1]).
  const std::vector<uint32_t>& cell_offsets() const { return offsets_; }

 private:
  // Each point's cell number in first-seen order (kNone: not finite), in
  // `cells` how many, and into `keys` (when given) each cell's key, by number.
  std::vector<uint32_t> number_cells(const std::vector<Eigen::Vector3f>& points, std::vector<uint64_t>* keys,
                                     size_t& cells) const;

  template <bool kClearance>
  Neighbour search(const Eigen::Vector3f& q, float radius_m, uint32_t stride_cap, float* clear2) const;

  struct Slot {
    uint64_t key = kEmpty;
    uint32_t begin = 0;
    uint32_t count = 0;
  };
  static constexpr uint64_t kEmpty = std::numeric_limits<uint64_t>::max();
  static constexpr int32_t kCoordLimit = (1 << 20) - 1;  // 21 bits per axis

  static uint64_t pack(int32_t x, int32_t y, int32_t z) {
    return (static_cast<uint64_t>(static_cast<uint32_t>(x + kCoordLimit + 1)) << 42) |
           (static_cast<uint64_t>(static_cast<uint32_t>(y + kCoordLimit + 1)) << 21) |
           static_cast<uint64_t>(static_cast<uint32_t>(z + kCoordLimit + 1));
  }
  int32_t coord(float v) const {
    const float c = v * inv_cell_;
    if (!(c > -static_cast<float>(kCoordLimit))) return -kCoordLimit;  // also NaN
    if (c > static_cast<float>(kCoordLimit)) return kCoordLimit;
    // floor without a libm call (x86-64's baseline has no SSE4.1 round).
    const int32_t i = static_cast<int32_t>(c);
    return c < static_cast<float>(i) ? i - 1 : i;
  }
  const Slot* find(uint64_t key) const {
    size_t i = static_cast<size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_);
    for (;;) {
      const Slot& s = slots_[i];
      if (s.key == key) return &s;
      if (s.key == kEmpty) return nullptr;
      i = (i + 1) & mask_;
    }
  }

  float cell_m_;
  float inv_cell_;
  size_t cell_count_ = 0;
  int shift_ = 64;
  size_t mask_ = 0;
  std::vector<Slot> slots_;
  std::vector<Eigen::Vector4f> sorted_;
  std::vector<uint32_t> index_;
  std::vector<uint32_t> offsets_;
};

template <bool kClearance>
inline VoxelGrid::Neighbour VoxelGrid::search(const Eigen::Vector3f& q, float radius_m, uint32_t stride_cap,
                                              float* clear2) const {
  Neighbour best;
  best.distance2_m2 = radius_m * radius_m;
  float second2 = best.distance2_m2;  // kClearance: the nearest other point (or skipped cell) so far
  // The cells the cube [q - r, q + r] touches (1 or 2 per axis when r <=
  // cell / 2), q's own cell first so that its best prunes the others: a
  // cell whose nearest face is farther than the best so far is not read.
  const int32_t c[3] = {coord(q.x()), coord(q.y()), coord(q.z())};
  int32_t lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = coord(q[a] - radius_m);
    hi[a] = coord(q[a] + radius_m);
  }
  const Eigen::Vector4f q4(q.x(), q.y(), q.z(), 0.0f);
  const auto gap = [&](int a, int32_t cell) {  // distance from q to the slab of `cell` along axis a
    if (cell == c[a]) return 0.0f;
    return cell < c[a] ? q[a] - static_cast<float>(cell + 1) * cell_m_ : static_cast<float>(cell) * cell_m_ - q[a];
  };
  const auto visit = [&](int32_t x, int32_t y, int32_t z, float box2) {
    if (box2 > best.distance2_m2) {
      if constexpr (kClearance) second2 = std::min(second2, box2);
      return;
    }
    const Slot* s = find(pack(x, y, z));
    if (s == nullptr) return;
    const Eigen::Vector4f* p = sorted_.data() + s->begin;
    const uint32_t step = (stride_cap > 0 && s->count > stride_cap) ? s->count / stride_cap : 1;
    for (uint32_t i = 0; i < s->count; i += step) {
      const float d2 = (p[i] - q4).squaredNorm();
      if (d2 <= best.distance2_m2) {
        if constexpr (kClearance) second2 = best.distance2_m2;
        best.distance2_m2 = d2;
        best.index = s->begin + i;
      } else if constexpr (kClearance) {
        second2 = std::min(second2, d2);
      }
    }
  };
  visit(c[0], c[1], c[2], 0.0f);
  for (int32_t x = lo[0]; x <= hi[0]; ++x) {
    const float gx = gap(0, x);
    for (int32_t y = lo[1]; y <= hi[1]; ++y) {
      const float gy = gap(1, y);
      for (int32_t z = lo[2]; z <= hi[2]; ++z) {
        if (x == c[0] && y == c[1] && z == c[2]) continue;
        const float gz = gap(2, z);
        visit(x, y, z, gx * gx + gy * gy + gz * gz);
      }
    }
  }
  if (best.index != kNone) best.index = index_[best.index];
  if constexpr (kClearance) *clear2 = second2;
  return best;
}

}  // namespace rise::semantic
