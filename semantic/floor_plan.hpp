#pragma once

// Walls and doorways from a 2D occupancy grid (a ROS map_server map, a grid
// rasterised from CARMEN laser logs, a 3D map projected to its wall band),
// extruded to a given height, so that a 2D-mapped building becomes the same
// Segmentation a registered cloud gives, and through it a world file.
//
// Method: the building's dominant directions from a histogram of the
// occupancy's gradient angles (not assumed to be two, nor at right angles);
// for each direction the grid is turned so that its walls run along the
// image rows; runs of occupied cells at least a wall's minimum length long
// are wall faces (perpendicular walls, thin diagonal clutter and specks are
// shorter along the rows and drop out); faces a wall's thickness apart with
// no free cell between them are one wall (seen from both sides), collinear
// faces join across door-wide gaps; a slanted wall in no direction of its
// own (too few edges for a peak) is a long, solid Hough line of occupied
// cells off every direction; a gap of door width with free space
// through it on both sides is a doorway (its far jamb a wall, or, read on
// the grid itself, a stub too short to be one), kept as an opening with a lintel
// at the door height, so the world file has wall above it.

#include "semantic/occupancy_grid.hpp"
#include "semantic/segmentation.hpp"

namespace rise::semantic {

struct FloorPlanSettings {
  double wall_height_m = 2.5;          ///< the extruded walls' top above the floor
  double door_height_m = 2.0;          ///< a doorway's lintel underside
  double door_min_width_m = 0.6;       ///< narrower gaps in a wall line are closed
  double door_max_width_m = 1.2;       ///< wider gaps (not doorways) split the wall
  double min_face_length_m = 0.5;      ///< shorter runs of occupied cells are not wall faces
  double min_wall_length_m = 1.0;      ///< shorter walls are furniture, jambs, recesses: left out
  double free_wall_min_length_m = 2.0; ///< ... and shorter ones standing free (no wall at an end or on their line)
  double min_wall_thickness_m = 0.1;   ///< a thinner measured slab is given this
  double max_wall_thickness_m = 0.5;   ///< faces up to this apart, nothing free between: one wall
  double noise_gap_m = 0.3;            ///< gaps up to this in a face are noise
  /// A face spread wider than a wall (clutter against it) is the wall of
  /// its own rows where this share of their cells lies within
  /// straight_within_m of their fitted line (a curved wall's do not) ...
  double straight_share = 0.4;
  double straight_within_m = 0.1;
  double trim_keep = 0.5;              ///< ... and that wall keeps this share of the face's length
  double collinear_offset_m = 0.15;    ///< collinear faces: centre lines at most this apart ...
  double angle_tolerance_rad = 6.0 * 3.14159265358979 / 180.0;  ///< directions closer than this are one
  double min_direction_share = 0.3;    ///< a direction holds this share of the strongest one's edges ...
  double minor_direction_share = 0.03; ///< ... or this share, and then only walls this long:
  double minor_wall_min_length_m = 3.0; ///< ... and so a slanted wall in no direction of its own:
  double slant_within_m = 0.15;        ///< its cells within this of its line ...
  double slant_min_solid = 0.85;       ///< ... along this share of its length at least
  double corner_gap_m = 0.4;           ///< a wall end this close to another wall's line meets it
  double door_clearance_m = 0.4;       ///< free space checked this deep either side of a doorway
  double door_min_free = 0.5;          ///< ... at least this share of it free
  double door_min_depth_m = 0.5;       ///< ... and free cells this far beyond the wall on both sides
  double corner_door_min_depth_m = 1.0; ///< ... this far for a gap beside a corner (a niche is no doorway)
  double door_jamb_m = 0.3;            ///< the wall either side of a doorway, this long, ...
  double door_jamb_solid = 0.6;        ///< ... has occupied cells along this share of it
};

/// The walls, doorways and floor of `grid`: Floor at z 0 over the free
/// cells' extent; no ceiling (a 2D map says nothing about one: the world
/// is open above its walls); Walls of settings.wall_height_m with their
/// measured thickness, each doorway an Opening (lintel at door_height_m)
/// and a Door (lintel = true, wall = its index); no stairs, no obstacles.
/// World frame = the grid's (metres). Throws std::invalid_argument for a
/// grid without free or occupied cells. Allocates; not for the cyclic path.
Segmentation segment_floor_plan(const OccupancyGrid& grid, const FloorPlanSettings& settings = {});

}  // namespace rise::semantic
