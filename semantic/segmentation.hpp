#pragma once

// Semantic entity identification in one registered cloud (world frame,
// metres, z up), after the seed paper's section 3: floor and ceiling from
// the height histogram and a plane fit; walls from a Hough transform of the
// points projected onto the floor plane, each line refined as a vertical
// plane; doors as wall gaps of door width with a "wall above door" (lintel)
// or a door panel in them; stairs as a set of parallel step edges at regular
// spacing; whatever is left above the floor as static obstacles.

#include <Eigen/Core>

#include <vector>

#include "semantic/cloud.hpp"

namespace rise::semantic {

struct SegmentationSettings {
  double height_bin_m = 0.01;          ///< floor/ceiling height histogram
  double plane_band_m = 0.03;          ///< floor/ceiling inliers: within this of the peak
  double min_ceiling_clearance_m = 1.8;
  double cell_m = 0.02;                ///< the floor-plane occupancy image
  double wall_band_margin_m = 0.3;     ///< walls from floor+margin .. ceiling-margin
  double wall_band_top_m = 2.3;        ///< ... but no higher above the floor than this
  double wall_min_tall_m = 1.2;        ///< a wall cell has points spread over this much height
  double wall_inlier_m = 0.025;        ///< a point belongs to a face within this
  double wall_min_length_m = 0.3;
  double wall_merge_gap_m = 0.3;       ///< gaps up to this along a face are closed
  double wall_min_thickness_m = 0.06;  ///< two parallel faces this far apart ...
  double wall_max_thickness_m = 0.4;   ///< ... up to this: the two sides of one wall
  double default_wall_thickness_m = 0.15;  ///< for a wall seen from one side only
  double corner_gap_m = 0.35;          ///< wall ends this close to another wall's face meet it
  double parallel_tolerance_rad = 2.0 * 3.14159265358979 / 180.0;
  /// A slab of points (a voxel map's wall with the shelves along it, a
  /// noisy sensor's) is found as several parallel lines: lines within this
  /// angle of each other, side by side with no floor seen between them ...
  double slab_tolerance_rad = 6.0 * 3.14159265358979 / 180.0;
  double slab_max_thickness_m = 0.5;   ///< ... are one wall up to this thick together;
  double slab_against_m = 0.3;         ///< a thicker pair, faces at most this apart: the shorter stands against the other (furniture)
  double wall_major_share = 0.3;       ///< a major direction holds this share of the most-walled one's length ...
  double wall_off_direction_min_length_m = 3.0;  ///< ... lines off them shorter than this are clutter
  double door_min_width_m = 0.6;
  double door_max_width_m = 1.2;
  double door_min_height_m = 1.6;      ///< lintel underside / panel top above the floor
  double door_max_sill_m = 0.3;        ///< an open gap is clear from this height up (else: a window's sill)
  int door_min_floor_cells = 3;        ///< 10 cm floor cells seen on each side of an open doorway
  /// Walls and doorways from segment_floor_plan() (floor_plan.hpp) on a
  /// grid of the cloud: occupied where a cell is tall (wall_min_tall_m over
  /// the wall band), free where the floor is seen with nothing standing on
  /// it below door_min_height_m; each doorway then checked in 3D for a lintel
  /// or a panel. Off: Hough lines refined as vertical planes.
  bool walls_from_floor_plan = false;
  double floor_plan_cell_m = 0.05;     ///< that grid's cells
  double stairs_min_riser_m = 0.1, stairs_max_riser_m = 0.25;
  double stairs_min_tread_m = 0.2, stairs_max_tread_m = 0.45;
  int stairs_min_steps = 3;
  double obstacle_cell_m = 0.05;       ///< clusters: connected cells of this size
  int obstacle_min_points = 40;
  double obstacle_min_height_m = 0.05;
  /// Obstacles are bounded things (furniture, clutter): a cluster larger
  /// than this in any direction is split on a finer grid, and what is
  /// still larger (structure the wall finder missed) is dropped.
  double obstacle_max_size_m = 3.0;
};

struct Floor {
  double height_m = 0.0;                       ///< plane height at the cloud's centre
  Eigen::Vector3d normal{0, 0, 1};             ///< least-squares plane normal, up
  Eigen::Vector2d min_m{0, 0}, max_m{0, 0};    ///< xy extent of its inlier points
  int points = 0;
  /// Its noise: how far under height_m the points within 30 cm of it reach
  /// (98th percentile). Nothing lies just under a floor, so they are the
  /// floor, and it is as thick above: 12 cm in a Kinect's OctoMap
  /// (freiburg1_360.bt), 6.6 cm in PCL's room_scan1.pcd.
  double noise_m = 0.0;
};

struct Ceiling {
  bool found = false;
  double height_m = 0.0;                       ///< underside, world z
  Eigen::Vector3d normal{0, 0, -1};            ///< down
  Eigen::Vector2d min_m{0, 0}, max_m{0, 0};
  int points = 0;
};

/// A door opening through a wall with wall above it (the lintel): like the
/// world file's opening, `at_m` along the wall from `from_m`.
struct Opening {
  double at_m = 0.0;
  double width_m = 0.0;
  double height_m = 0.0;  ///< above the floor: the lintel's underside
};

/// A straight wall, its centre line as the world file has it: from_m..to_m
/// where it meets another wall, or thickness/2 short of its last point at a
/// free end (the box is lengthened by thickness/2 past each end).
struct Wall {
  Eigen::Vector2d from_m{0, 0}, to_m{0, 0};
  double height_m = 0.0;       ///< top above the floor
  double thickness_m = 0.0;
  bool both_faces_seen = false;
  std::vector<Opening> openings;  ///< sorted by at_m
  int points = 0;              ///< inlier points of its faces

  double length_m() const { return (to_m - from_m).norm(); }
  /// Unit direction from_m → to_m.
  Eigen::Vector2d direction() const { return (to_m - from_m).normalized(); }
};

/// A door: a gap of door width in a wall line, with wall above it (the
/// lintel; then it is one of the wall's openings) or a closed door panel in
/// it (then the gap lies between two walls, as in the world file).
struct Door {
  Eigen::Vector2d center_m{0, 0};  ///< middle of the gap, on the wall's centre line
  double yaw_rad = 0.0;            ///< along the wall
  double width_m = 0.0;            ///< the clear gap
  double height_m = 0.0;           ///< lintel underside, or the panel's top
  double wall_thickness_m = 0.0;
  bool lintel = false;             ///< wall above the door seen
  bool panel = false;              ///< a closed panel seen in the gap
  int wall = -1;                   ///< the wall whose opening it is, or -1
  int wall_before = -1, wall_after = -1;  ///< the walls either side of the gap, or -1
};

/// A straight staircase, as the world file has one: `start_m` is the middle
/// of the first riser's foot, the steps climb along yaw_rad.
struct Stairs {
  Eigen::Vector2d start_m{0, 0};
  double yaw_rad = 0.0;
  int steps = 0;
  double riser_m = 0.0;
  double tread_m = 0.0;
  double width_m = 0.0;
  double landing_m = 0.0;       ///< flat top beyond the last tread
  double rms_m = 0.0;           ///< fit residual of the step edges
  int points = 0;
};

/// A static obstacle: the oriented box around a point cluster.
struct Obstacle {
  Eigen::Vector3d center_m{0, 0, 0};
  Eigen::Vector3d size_m{0, 0, 0};
  double yaw_rad = 0.0;
  int points = 0;
};

struct Segmentation {
  Floor floor;
  Ceiling ceiling;
  std::vector<Wall> walls;
  std::vector<Door> doors;
  std::vector<Stairs> stairs;
  std::vector<Obstacle> obstacles;
  /// Clusters larger than obstacle_max_size_m, or whose box would shut a
  /// door's passage their points leave open, that were dropped, not
  /// obstacles.
  int oversize_clusters_dropped = 0;
};

/// Finds the entities in `cloud` (world frame, z up, metres; levelled: the
/// floor within a few degrees of horizontal). Throws std::invalid_argument
/// when the cloud is empty or has no floor. Allocates; not for the cyclic
/// path.
Segmentation segment(const Cloud& cloud, const SegmentationSettings& settings = {});

/// The rotation about the origin that makes the floor (as segment() finds
/// it: the lowest large peak of the height histogram, plane-fitted)
/// exactly horizontal: for a cloud from a sensor tilted by a few degrees.
/// Throws std::invalid_argument when there is no floor.
Eigen::Matrix3d levelling_rotation(const Cloud& cloud, const SegmentationSettings& settings = {});

}  // namespace rise::semantic
