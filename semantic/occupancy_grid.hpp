#pragma once

// 2D occupancy grids: the maps most mobile robots make (ROS map_server's
// `.pgm` + `.yaml`, a grid rasterised from CARMEN laser logs), and the
// floor plan the 3D engine projects a registered cloud onto. One cell per
// `resolution_m` square, trinary as map_server publishes it in its default
// ("trinary") mode: unknown, free, occupied.
//
// Readers (occupancy_grid.cpp) throw std::runtime_error naming the file and
// the line ("map.yaml:3: resolution: ...") or the byte offset in binary data.

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace rise::semantic {

enum class CellState : int8_t { Unknown = -1, Free = 0, Occupied = 100 };

struct OccupancyGrid {
  double resolution_m = 0.05;            ///< side of one cell
  Eigen::Vector2d origin_m{0, 0};        ///< world x, y of cell (0, 0)'s lower-left corner
  int width = 0;                         ///< cells along +x
  int height = 0;                        ///< cells along +y
  std::vector<CellState> cells;          ///< row-major, row 0 the lowest y: cells[row * width + col]

  bool contains(int col, int row) const { return col >= 0 && row >= 0 && col < width && row < height; }
  CellState at(int col, int row) const { return cells[static_cast<size_t>(row) * width + col]; }
  CellState& at(int col, int row) { return cells[static_cast<size_t>(row) * width + col]; }
  /// World x, y of the cell's centre.
  Eigen::Vector2d center(int col, int row) const {
    return origin_m + resolution_m * Eigen::Vector2d(col + 0.5, row + 0.5);
  }
  /// The cell holding world point `xy` (may be outside: check contains()).
  Eigen::Vector2i cell_of(const Eigen::Vector2d& xy) const {
    const Eigen::Vector2d c = (xy - origin_m) / resolution_m;
    return {static_cast<int>(std::floor(c.x())), static_cast<int>(std::floor(c.y()))};
  }
};

}  // namespace rise::semantic
