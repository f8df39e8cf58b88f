#pragma once

// The stages of segment() (segmentation.cpp), one file each: floor and
// ceiling, walls and doors, stairs and obstacles. Internal to rise_semantic.

#include <Eigen/Core>

#include <utility>
#include <vector>

#include "semantic/segmentation.hpp"

namespace rise::semantic::detail {

/// q-quantile (0..1) of v (copied; nearest rank). 0 for an empty v.
double quantile(std::vector<double> v, double q);

/// A 2D line through `point` along the unit `direction`; `normal` is the
/// direction turned +90°.
struct Line2 {
  Eigen::Vector2d point{0, 0};
  Eigen::Vector2d direction{1, 0};
  Eigen::Vector2d normal{0, 1};
  double offset(const Eigen::Vector2d& p) const { return normal.dot(p - point); }
  double along(const Eigen::Vector2d& p) const { return direction.dot(p - point); }
};

/// Throws std::invalid_argument when a grid of `cell_m` over `extent_m`
/// would exceed 16 million cells (a cloud with far outliers).
void check_grid(const Eigen::Vector2d& extent_m, double cell_m, const char* what);

/// Total least squares (PCA) line through the points' xy.
Line2 fit_line(const std::vector<Eigen::Vector2d>& xy);

/// The same for parallel lines, one offset each: their common direction
/// (the major axis of each line's scatter about its own mean, summed),
/// through the mean of all their points.
Line2 fit_parallel_lines(const std::vector<std::vector<Eigen::Vector2d>>& lines);

void find_floor_and_ceiling(const Cloud& cloud, const SegmentationSettings& s, Floor& floor, Ceiling& ceiling);

/// What fills a gap of door width in a wall (doors.cpp).
struct GapReport {
  bool lintel = false;      ///< wall above the door: covered layers down from the wall's top
  bool panel = false;       ///< a door panel: covered layers from 0.3 m to the door's minimum height
  bool free_below = false;  ///< nothing between 0.3 m and the door's minimum height
  bool window = false;      ///< no panel, but something across the gap above door_max_sill_m (a sill)
  double lintel_bottom_m = 0, panel_top_m = 0, sill_m = 0;  ///< above the floor; sill_m 0: none
};

/// The points of a wall's slab (along the wall, height above the floor)
/// over the gap g0..g1, in square cells of cell_m, below the wall's top.
GapReport inspect_gap(const std::vector<std::pair<double, double>>& slab_along_height, double g0, double g1,
                      double top_m, double cell_m, const SegmentationSettings& s);

/// Walls, and the doors in their gaps.
void find_walls_and_doors(const Cloud& cloud, const SegmentationSettings& s, const Floor& floor,
                          const Ceiling& ceiling, std::vector<Wall>& walls, std::vector<Door>& doors);

/// Clusters what is left (not floor, ceiling, walls, doors): stairs, and
/// the rest as obstacles; `dropped` counts the clusters too large for one.
void find_stairs_and_obstacles(const Cloud& cloud, const SegmentationSettings& s, const Floor& floor,
                               const Ceiling& ceiling, const std::vector<Wall>& walls,
                               const std::vector<Door>& doors, std::vector<Stairs>& stairs,
                               std::vector<Obstacle>& obstacles, int& dropped);

}  // namespace rise::semantic::detail
