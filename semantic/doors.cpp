// Doors (seed paper, section 3): a gap of door width in a wall is a door
// when there is wall above it (the "wall above door", a lintel) with free
// space below, or a door panel standing in it. A gap with wall below it up
// to a sill (a window) is not. find_walls_and_doors() (walls.cpp) finds the
// gaps and checks that the floor is seen through an open one; this looks
// into one.

#include <algorithm>
#include <vector>

#include "semantic/segmentation_internal.hpp"

namespace rise::semantic::detail {

// Height profile of the points in a wall's slab over the gap (heights above
// the floor), in square cells of cell_m (the faces' point spacing or more).
GapReport inspect_gap(const std::vector<std::pair<double, double>>& slab_sz, double g0, double g1, double top_m,
                      double cell_m, const SegmentationSettings& s) {
  GapReport rep;
  const double a0 = g0 + cell_m, a1 = g1 - cell_m;
  if (a1 <= a0 || top_m <= 0) return rep;
  const int cols = std::max(1, static_cast<int>((a1 - a0) / cell_m));
  const int layers = std::max(1, static_cast<int>(top_m / cell_m));
  std::vector<std::vector<char>> hit(static_cast<std::size_t>(layers), std::vector<char>(static_cast<std::size_t>(cols), 0));
  std::vector<double> zs;
  for (const auto& [sa, z] : slab_sz) {
    if (sa < a0 || sa >= a1 || z < 0 || z >= top_m) continue;
    const int c = std::min(cols - 1, static_cast<int>((sa - a0) / cell_m));
    hit[static_cast<std::size_t>(std::min(layers - 1, static_cast<int>(z / cell_m)))][static_cast<std::size_t>(c)] = 1;
    zs.push_back(z);
  }
  const auto coverage = [&](int layer) {
    int n = 0;
    for (char h : hit[static_cast<std::size_t>(layer)]) n += h;
    return static_cast<double>(n) / cols;
  };
  // Wall above the door: covered layers from just under the wall's top down.
  int k = layers - 2;
  while (k >= 0 && coverage(k) >= 0.6) --k;
  const double lintel_bottom = (k + 1) * cell_m;
  if (k < layers - 2 && lintel_bottom >= s.door_min_height_m) {
    rep.lintel = true;
    std::vector<double> above;
    for (double z : zs)
      if (z >= lintel_bottom - cell_m) above.push_back(z);
    rep.lintel_bottom_m = quantile(above, 0.02);
  }
  // A panel in the gap: covered from 0.3 m up to the door's minimum height.
  const int k0 = static_cast<int>(0.3 / cell_m), k1 = std::min(layers - 1, static_cast<int>(s.door_min_height_m / cell_m));
  int covered = 0, empty = 0;
  for (int j = k0; j < k1; ++j) {
    covered += coverage(j) >= 0.6;
    empty += coverage(j) < 0.2;
  }
  const int n = std::max(1, k1 - k0);
  rep.free_below = empty >= 0.9 * n;
  // Something across the gap between a threshold's height and a door's (a
  // window's sill, seen from above or from the side): not an open doorway.
  for (int j = std::max(0, static_cast<int>(s.door_max_sill_m / cell_m)); j < k1; ++j)
    if (coverage(j) >= 0.6) rep.sill_m = (j + 1) * cell_m;
  rep.window = rep.sill_m > 0 && covered < 0.8 * n;
  if (covered >= 0.8 * n) {
    rep.panel = true;
    int j = k0;
    while (j < layers - 1 && coverage(j) >= 0.6 && (!rep.lintel || (j + 1) * cell_m < rep.lintel_bottom_m)) ++j;
    std::vector<double> below;
    for (double z : zs)
      if (z <= (j + 1) * cell_m) below.push_back(z);
    rep.panel_top_m = quantile(below, 0.98);
  }
  return rep;
}

}  // namespace rise::semantic::detail
