#include "semantic/voxel_grid.hpp"

#include <algorithm>
#include <bit>
#include <stdexcept>

namespace rise::semantic {

VoxelGrid::VoxelGrid(const std::vector<Eigen::Vector3f>& points, float cell_m, int max_points_per_cell)
    : cell_m_(cell_m), inv_cell_(1.0f / cell_m) {
  if (!(cell_m > 0.0f) || !std::isfinite(cell_m) || !std::isfinite(inv_cell_))
    throw std::invalid_argument("VoxelGrid: cell_m must be positive and finite");
  // Each point's cell number (one pass over a hash table), then a counting
  // sort by it. Runs in first-seen order: a scan's points arrive sweep by
  // sweep, so neighbouring cells, and the queries of neighbouring source
  // points, stay close in memory.
  std::vector<uint64_t> keys;
  const std::vector<uint32_t> numbers = number_cells(points, &keys, cell_count_);
  const uint32_t cap = max_points_per_cell > 0 ? static_cast<uint32_t>(max_points_per_cell) : kNone;
  offsets_.assign(cell_count_ + 1, 0);
  for (const uint32_t n : numbers)
    if (n != kNone && offsets_[n + 1] < cap) ++offsets_[n + 1];
  for (size_t c = 0; c < cell_count_; ++c) offsets_[c + 1] += offsets_[c];
  sorted_.resize(offsets_.back());
  index_.resize(offsets_.back());
  std::vector<uint32_t> fill(offsets_.begin(), offsets_.end() - 1);
  for (size_t i = 0; i < points.size(); ++i) {
    const uint32_t n = numbers[i];
    if (n == kNone || fill[n] == offsets_[n + 1]) continue;
    const uint32_t at = fill[n]++;
    sorted_[at] = Eigen::Vector4f(points[i].x(), points[i].y(), points[i].z(), 0.0f);
    index_[at] = static_cast<uint32_t>(i);
  }
  // Queries probe this table at random: sized to the cells (load 0.4 ..
  // 0.8; not twice the points) so that it stays in cache.
  const size_t capacity = std::bit_ceil(std::max<size_t>(16, cell_count_ + cell_count_ / 4));
  slots_.assign(capacity, Slot{});
  mask_ = capacity - 1;
  shift_ = 64 - std::countr_zero(capacity);
  for (size_t c = 0; c < cell_count_; ++c) {
    size_t i = static_cast<size_t>((keys[c] * 0x9E3779B97F4A7C15ull) >> shift_);
    while (slots_[i].key != kEmpty) i = (i + 1) & mask_;
    slots_[i] = {keys[c], offsets_[c], offsets_[c + 1] - offsets_[c]};
  }
}

std::vector<uint32_t> VoxelGrid::number_cells(const std::vector<Eigen::Vector3f>& points, std::vector<uint64_t>* keys,
                                              size_t& cells) const {
  const size_t capacity = std::bit_ceil(std::max<size_t>(16, points.size() * 2));
  const size_t mask = capacity - 1;
  const int shift = 64 - std::countr_zero(capacity);
  struct Entry {
    uint64_t key = kEmpty;
    uint32_t number = kNone;
  };
  std::vector<Entry> table(capacity);
  std::vector<uint32_t> numbers(points.size(), kNone);
  uint32_t next = 0;
  for (size_t k = 0; k < points.size(); ++k) {
    const auto& p = points[k];
    if (!p.allFinite()) continue;
    const uint64_t key = pack(coord(p.x()), coord(p.y()), coord(p.z()));
    size_t i = static_cast<size_t>((key * 0x9E3779B97F4A7C15ull) >> shift);
    while (table[i].key != key && table[i].key != kEmpty) i = (i + 1) & mask;
    if (table[i].key == kEmpty) {
      table[i] = {key, next++};
      if (keys != nullptr) keys->push_back(key);
    }
    numbers[k] = table[i].number;
  }
  cells = next;
  return numbers;
}

size_t VoxelGrid::count_cells(const std::vector<Eigen::Vector3f>& points, float cell_m, size_t limit, size_t* read) {
  const VoxelGrid empty({}, cell_m);  // validates cell_m; its coord() and pack() map a point to its key
  const size_t capacity = std::bit_ceil(std::max<size_t>(16, std::min(points.size(), limit + 1) * 2));
  const size_t mask = capacity - 1;
  const int shift = 64 - std::countr_zero(capacity);
  std::vector<uint64_t> keys(capacity, kEmpty);
  size_t cells = 0, n = 0;
  for (const auto& p : points) {
    ++n;
    if (!p.allFinite()) continue;
    const uint64_t key = pack(empty.coord(p.x()), empty.coord(p.y()), empty.coord(p.z()));
    size_t i = static_cast<size_t>((key * 0x9E3779B97F4A7C15ull) >> shift);
    while (keys[i] != key && keys[i] != kEmpty) i = (i + 1) & mask;
    if (keys[i] == kEmpty) {
      keys[i] = key;
      if (++cells > limit) break;
    }
  }
  if (read != nullptr) *read = n;
  return cells;
}

std::vector<uint32_t> VoxelGrid::cell_numbers(const std::vector<Eigen::Vector3f>& points, float cell_m, size_t& cells) {
  const VoxelGrid empty({}, cell_m);  // validates cell_m; its coord() and pack() map a point to its key
  return empty.number_cells(points, nullptr, cells);
}

float VoxelGrid::face_gap(const Eigen::Vector3f& q) const {
  float face = cell_m_;
  for (int a = 0; a < 3; ++a) {
    const float lo = static_cast<float>(coord(q[a])) * cell_m_;
    face = std::min({face, q[a] - lo, lo + cell_m_ - q[a]});
  }
  return std::max(0.0f, face - 1e-6f * (q.cwiseAbs().maxCoeff() + cell_m_));  // float rounding of the cell's faces
}

void VoxelGrid::k_nearest(const Eigen::Vector3f& q, int k, std::vector<Neighbour>& out, int max_rings) const {
  out.clear();
  if (k <= 0 || !q.allFinite()) return;
  const size_t want = static_cast<size_t>(k);
  const auto closer = [](const Neighbour& a, const Neighbour& b) { return a.distance2_m2 < b.distance2_m2; };
  const int32_t cx = coord(q.x()), cy = coord(q.y()), cz = coord(q.z());
  const Eigen::Vector4f q4(q.x(), q.y(), q.z(), 0.0f);
  // Ring by ring (the shell of cells at Chebyshev distance `ring`): a point
  // outside rings 0..R is farther than R cells plus q's distance to its own
  // cell's nearest face, so the k best are final once the k-th is within that.
  const float face = face_gap(q);
  for (int ring = 0; ring <= max_rings; ++ring) {
    for (int32_t dx = -ring; dx <= ring; ++dx)
      for (int32_t dy = -ring; dy <= ring; ++dy)
        for (int32_t dz = -ring; dz <= ring; ++dz) {
          if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != ring) continue;
          const int32_t x = cx + dx, y = cy + dy, z = cz + dz;
          if (std::max({std::abs(x), std::abs(y), std::abs(z)}) > kCoordLimit) continue;
          const Slot* s = find(pack(x, y, z));
          if (s == nullptr) continue;
          for (uint32_t i = 0; i < s->count; ++i) {
            const Neighbour n{s->begin + i, (sorted_[s->begin + i] - q4).squaredNorm()};
            if (out.size() < want) {
              out.push_back(n);
              std::push_heap(out.begin(), out.end(), closer);
            } else if (n.distance2_m2 < out.front().distance2_m2) {
              std::pop_heap(out.begin(), out.end(), closer);
              out.back() = n;
              std::push_heap(out.begin(), out.end(), closer);
            }
          }
        }
    const float reach = static_cast<float>(ring) * cell_m_ + face;
    if (out.size() == want && out.front().distance2_m2 <= reach * reach) break;
  }
  std::sort_heap(out.begin(), out.end(), closer);
  for (auto& n : out) n.index = index_[n.index];
}

}  // namespace rise::semantic
