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
#include <string_view>
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

/// ROS map_server's map: its YAML (image, resolution, origin [x, y, yaw],
/// negate, occupied_thresh, free_thresh, mode trinary|scale|raw; wiki.ros.org/map_server)
/// and the image it names (PGM P5/P2 8 or 16 bit, PNG, anything OpenCV reads),
/// relative to the YAML's folder; `image_path`, when given, replaces it (a map
/// saved under another name). Cells as map_server's trinary mode makes them:
/// p = (max - v) / max (v / max with negate), occupied when p > occupied_thresh,
/// free when p < free_thresh, unknown between. "scale" gives the same three
/// states (its grey levels between the thresholds are unknown here); "raw"
/// reads v as the occupancy percentage (0 free .. 100 occupied, above 100
/// unknown) against the same thresholds. A yaw other than 0 is refused:
/// map_server itself ignores it, so a rotated map would be silently wrong.
/// Image row 0 is the top (highest y): the grid's row 0 is the image's last.
OccupancyGrid read_ros_map(const std::string& yaml_path, const std::string& image_path = "");

/// One 2D laser scan with the laser's pose in the map frame.
struct LaserScan2D {
  double time_s = 0;
  Eigen::Vector3d pose{0, 0, 0};  ///< x, y (m), theta (rad) of the laser in the map frame
  double start_angle_rad = 0;     ///< bearing of ranges[0] in the laser frame
  double angle_step_rad = 0;      ///< bearing increment from one beam to the next
  double max_range_m = 0;         ///< readings >= this are no-returns
  std::vector<float> ranges;      ///< m
};

/// The laser scans of a CARMEN log (carmen.sourceforge.net, "logger" file
/// format), plain or gzip: FLASER lines (`FLASER n r1..rn x y theta odom_x
/// odom_y odom_theta ipc_timestamp hostname logger_timestamp`, `x y theta`
/// the laser's pose; CARMEN's bearings: n = 180/360 beams at 1/0.5 deg from
/// -90 deg, n = 181/361 over -90..+90 deg inclusive, other n over 180 deg) and
/// ROBOTLASER1 lines (their own start, step and max range); other messages
/// skipped. A FLASER's max range is PARAM robot_front_laser_max when the log
/// has it, otherwise the log's largest reading: the SICK writes its
/// no-return code there (81.83, 81.91 or a configured 50 m).
std::vector<LaserScan2D> read_carmen_log(const std::string& path);
/// The same on the log's text (`path` only names it in errors): the fuzz target's entry point.
std::vector<LaserScan2D> parse_carmen_log(const std::string& path, std::string_view text);

/// How scans become a grid: log-odds per cell, a hit where a beam ends, a
/// miss in each cell it crosses (Thrun, Burgard, Fox, "Probabilistic
/// Robotics", 9.2), clamped, then thresholded into the three states.
struct ScanGridSettings {
  double hit_logodds = 0.85;       ///< p = 0.7
  double miss_logodds = -0.4;      ///< p = 0.4
  double clamp_logodds = 3.5;      ///< |L| never exceeds this: a cell can change its mind
  double occupied_logodds = 0.5;   ///< L above this is occupied
  double free_logodds = -0.5;      ///< L below this is free
  double max_hit_range_m = 40;     ///< longer readings only clear space (their bearing error smears walls)
  double no_return_free_m = 8;     ///< a no-return clears free space this far along its beam
};

/// A trinary grid, `resolution_m` per cell, covering the laser poses and
/// every cell a beam touched; cells no beam touched are unknown.
OccupancyGrid grid_from_scans(const std::vector<LaserScan2D>& scans, double resolution_m = 0.05,
                              const ScanGridSettings& settings = {});

}  // namespace rise::semantic
