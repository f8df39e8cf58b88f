#pragma once

// Environment model generation (seed paper, section 3): from the semantic
// net, the simulator's world file (sim/README.md "World file v1": walls as
// boxes with door openings, hinged doors, stairs, the ceiling, obstacles as
// props, a robot start), a top-down PNG map with labels, an SDF world
// (SDFormat 1.6, static box models, for Gazebo) and a Wavefront OBJ mesh.
// The world file is the only link to sim/: nothing here includes it.

#include <Eigen/Core>

#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "semantic/cloud.hpp"
#include "semantic/occupancy_grid.hpp"
#include "semantic/semantic_net.hpp"

namespace rise::semantic {

struct ExportSettings {
  std::string world_name = "semantic";
  /// x, y (m), yaw (rad); none: chosen by robot_start().
  std::optional<Eigen::Vector3d> robot_start;
  /// Where the robot stood (x, y, yaw): the scan poses, when known.
  std::vector<Eigen::Vector3d> known_poses;
  /// The floor plan: free where the floor was seen and nothing stands at
  /// the robot's height. From a 2D map, or floor_plan_of() a cloud; none:
  /// the floor's extent counts as free.
  std::shared_ptr<const OccupancyGrid> floor_plan;
  double robot_half_width_m = 0.4;
  double robot_margin_m = 0.2;        ///< the start is half-width + margin from everything
  double robot_height_m = 1.0;        ///< floor_plan_of: what is lower blocks the robot
  double floor_plan_cell_m = 0.05;    ///< floor_plan_of's cells
  double ceiling_thickness_m = 0.1;
  double door_thickness_m = 0.04;
  double door_open_max_deg = 100.0;
  double door_break_torque_nm = 900.0;
  double door_mass_kg = 20.0;
  double map_px_per_m = 50.0;         ///< PNG scale
};

/// One solid of the model: a box `size_m` (along yaw, across, up) centred
/// at `center_m`, named after its entity (`name`), of `kind` ("wall",
/// "door", "stairs", "ceiling", "floor", "obstacle").
struct ModelBox {
  std::string name;
  std::string kind;
  Eigen::Vector3d center_m{0, 0, 0};
  Eigen::Vector3d size_m{0, 0, 0};
  double yaw_rad = 0.0;
};

/// The solids as the simulator builds them from the world file: walls
/// lengthened by their thickness and split around openings (with lintels),
/// stair blocks from the floor up and the landing, closed door panels,
/// the ceiling slab, obstacles, and a 5 cm floor slab under the floor.
std::vector<ModelBox> model_boxes(const SemanticNet& net, const ExportSettings& settings = {});

/// robot_start()'s refusal: no place with room for the robot.
struct NoRobotStart : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Where the robot starts, x, y, yaw: settings.robot_start; or the first
/// of the known poses with robot_half_width_m (it stood there) clear of the
/// solids (model_boxes below robot_height_m) and the floor plan's occupied
/// cells; or the point with the most clearance in the largest region of the
/// floor plan (free cells, without the solids) where that clearance fits,
/// clear of unknown space too, facing the nearest door. Throws
/// NoRobotStart when no place has the clearance.
Eigen::Vector3d robot_start(const SemanticNet& net, const ExportSettings& settings = {});

/// The floor plan of `cloud` as `seg` found it, in cells of
/// floor_plan_cell_m over the floor's and the cloud's extent: free where
/// the floor was seen, occupied where a point lies between 2 cm above the
/// floor's band and robot_height_m, unknown elsewhere. The band is the
/// floor's noise as the points under it show it (at least 3 cm). Small
/// holes between a far floor's scan lines are closed.
OccupancyGrid floor_plan_of(const Cloud& cloud, const Segmentation& seg, const ExportSettings& settings = {});

/// The world file's text (YAML, the format sim/world_description.cpp reads).
std::string world_yaml(const SemanticNet& net, const ExportSettings& settings = {});
/// SDFormat 1.6: a <world> with a ground plane, a sun and one static
/// <model> per solid.
std::string sdf_world(const SemanticNet& net, const ExportSettings& settings = {});
/// Wavefront OBJ: one object (8 vertices, 6 quads) per solid.
std::string obj_mesh(const SemanticNet& net, const ExportSettings& settings = {});

/// A label on the map: the entity's name (or its abbreviation, "d3" for
/// door_3), its text box in pixels (x right, y down from the top-left).
struct MapLabel {
  int entity = -1;  ///< id in the net
  std::string text;
  int x = 0, y = 0, width = 0, height = 0;
};

/// Where write_map_png puts things. The map spans the floor and the solids
/// plus 0.5 m, north (+y) up; the legend (colours, and a scale bar of
/// scale_bar_m) sits in the corner with the least drawn on it; each label
/// beside its entity where it overlaps no other label, nor the legend, and
/// covers the least; labels with no such place are left out.
struct MapLayout {
  Eigen::Vector2d min_m{0, 0}, max_m{0, 0};  ///< world extent shown
  double px_per_m = 0.0;
  int cols = 0, rows = 0;
  std::vector<MapLabel> labels;
  int legend_x = 0, legend_y = 0, legend_width = 0, legend_height = 0;
  double scale_bar_m = 0.0;
  int scale_bar_x0 = 0, scale_bar_x1 = 0, scale_bar_y = 0;  ///< its ends, pixels
};

/// The layout write_map_png() draws (same arguments).
MapLayout map_layout(const SemanticNet& net, const Cloud* cloud = nullptr, const ExportSettings& settings = {});

/// Map colours (BGR, as cv::imread gives them).
namespace map_colour {
constexpr unsigned char kFree[3] = {255, 255, 255};
constexpr unsigned char kUnknown[3] = {215, 215, 215};
constexpr unsigned char kOccupied[3] = {140, 140, 140};
constexpr unsigned char kWall[3] = {30, 30, 30};
constexpr unsigned char kDoor[3] = {40, 170, 40};
constexpr unsigned char kStairs[3] = {230, 160, 90};
constexpr unsigned char kObstacle[3] = {40, 90, 230};
}  // namespace map_colour

/// The top-down map: the floor plan (settings.floor_plan, or the cloud's
/// when given) free white, unknown light grey, occupied grey; walls black,
/// doors green, stairs blue with their step lines, obstacles orange-red;
/// labels, the legend and the scale bar as map_layout() places them.
void write_map_png(const std::string& path, const SemanticNet& net, const Cloud* cloud = nullptr,
                   const ExportSettings& settings = {});

/// Writes `text` to `path`; throws std::runtime_error "path: message".
void write_text_file(const std::string& path, const std::string& text);

}  // namespace rise::semantic
