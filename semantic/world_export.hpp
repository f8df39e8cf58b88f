#pragma once

// Environment model generation (seed paper, section 3): from the semantic
// net, the simulator's world file (sim/README.md "World file v1": walls as
// boxes with door openings, hinged doors, stairs, the ceiling, obstacles as
// props, a robot start), a top-down PNG map with labels, an SDF world
// (SDFormat 1.6, static box models, for Gazebo) and a Wavefront OBJ mesh.
// The world file is the only link to sim/: nothing here includes it.

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

#include "semantic/cloud.hpp"
#include "semantic/semantic_net.hpp"

namespace rise::semantic {

struct ExportSettings {
  std::string world_name = "semantic";
  /// x, y (m), yaw (rad); none: in free space in front of the first door.
  std::optional<Eigen::Vector3d> robot_start;
  double robot_clearance_m = 0.8;     ///< free radius around the chosen start
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

/// Where the robot starts: settings.robot_start, or 1–2.5 m in front of the
/// first door (facing it) where nothing is within robot_clearance_m, or
/// the clearest point of the floor. x, y, yaw.
Eigen::Vector3d robot_start(const SemanticNet& net, const ExportSettings& settings = {});

/// The world file's text (YAML, the format sim/world_description.cpp reads).
std::string world_yaml(const SemanticNet& net, const ExportSettings& settings = {});
/// SDFormat 1.6: a <world> with a ground plane, a sun and one static
/// <model> per solid.
std::string sdf_world(const SemanticNet& net, const ExportSettings& settings = {});
/// Wavefront OBJ: one object (8 vertices, 6 quads) per solid.
std::string obj_mesh(const SemanticNet& net, const ExportSettings& settings = {});

/// The top-down map: the cloud's occupancy in grey (when given), walls
/// black, doors green, stairs blue with their step lines, obstacles red,
/// each labelled with its name; north (+y) up.
void write_map_png(const std::string& path, const SemanticNet& net, const Cloud* cloud = nullptr,
                   const ExportSettings& settings = {});

/// Writes `text` to `path`; throws std::runtime_error "path: message".
void write_text_file(const std::string& path, const std::string& text);

}  // namespace rise::semantic
