#pragma once

// The environment: a ground plane, an optional ceiling, static boxes, props
// and walls (with door openings), hinged doors, staircases, movable objects
// and named regions (the world file format is
// documented in sim/README.md).

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace rise::sim {

struct BoxObstacle {
  std::string name;
  std::array<double, 3> center_m{};  ///< world frame, z up
  std::array<double, 3> size_m{1, 1, 1};
  double yaw_rad = 0.0;
};

/// A static prop (a shelf, a cabinet): a box labelled with its `kind`;
/// events and contacts name it by `box.name`.
struct Prop {
  BoxObstacle box;
  std::string kind;
};

/// A door opening through a wall, from the floor up to `height_m`; its first
/// side is `at_m` along the wall from the wall's `from_m`.
struct WallOpening {
  double at_m = 0.0;
  double width_m = 0.9;
  double height_m = 2.0;
};

/// A straight static wall standing on the ground from `from_m` to `to_m`.
struct Wall {
  std::string name;
  std::array<double, 2> from_m{};
  std::array<double, 2> to_m{};
  double height_m = 2.5;
  double thickness_m = 0.15;
  std::vector<WallOpening> openings;  ///< sorted by at_m, disjoint, within the wall, at most height_m high
};

/// The static boxes a wall is built of, each named after the wall (world
/// frame, z up). The wall is lengthened by its thickness, thickness/2 past
/// each end, so that walls meeting at a corner close it; each opening
/// leaves a gap from the floor to its height, with a lintel above it when
/// it is lower than the wall.
std::vector<BoxObstacle> wall_boxes(const Wall& wall);

/// A static slab whose underside is at `height_m`, over `min_m`..`max_m`
/// (world xy).
struct Ceiling {
  double height_m = 2.6;
  double thickness_m = 0.1;
  std::array<double, 2> min_m{};
  std::array<double, 2> max_m{};
};

/// The ceiling slab as a box named "ceiling" (events and contacts name it so).
BoxObstacle ceiling_box(const Ceiling& ceiling);

/// A door panel on a vertical hinge. Closed, the panel runs from the hinge
/// along `yaw_rad`; it swings ±open_max_rad. The hinge breaks when its load
/// (constraint torque about the hinge) stays above break_torque_nm for
/// break_time_ms.
struct Door {
  std::string name;
  std::array<double, 2> hinge_m{};
  double width_m = 0.9;
  double height_m = 2.0;
  double thickness_m = 0.04;
  double yaw_rad = 0.0;
  double open_max_rad = 1.6;
  double break_torque_nm = 1500.0;
  double break_time_ms = 20.0;
  double mass_kg = 20.0;
  double friction_torque_nm = 2.0;  ///< hinge friction
  double return_nm_per_rad = 1.0;   ///< door closer
};

/// A straight staircase of static blocks climbing along `yaw_rad` from
/// `start_m` (middle of the first riser's foot), ending in a landing.
struct Stairs {
  std::string name;
  std::array<double, 2> start_m{};
  double yaw_rad = 0.0;
  int steps = 6;
  double riser_m = 0.17;
  double tread_m = 0.28;
  double width_m = 1.2;
  double landing_m = 1.5;  ///< landing length along the climb direction

  double landing_height_m() const { return steps * riser_m; }
};

/// A free box that the robot can push or carry.
struct MovableObject {
  std::string name;
  std::array<double, 3> size_m{0.3, 0.3, 0.3};
  double mass_kg = 5.0;
  std::array<double, 3> center_m{};
};

/// An axis-aligned box of interest (enter / leave events).
struct Region {
  std::string name;
  std::array<double, 3> min_m{};
  std::array<double, 3> max_m{};
};

/// Where a robot's base starts on the floor.
struct RobotStart {
  std::array<double, 2> xy_m{0, 0};
  double yaw_rad = 0.0;
};

struct WorldDescription {
  std::string name = "yard";
  std::string file;
  double ground_friction = 1.0;
  std::optional<Ceiling> ceiling;
  std::vector<BoxObstacle> boxes;
  std::vector<Prop> props;
  std::vector<Wall> walls;
  std::vector<Door> doors;
  std::vector<Stairs> stairs;
  std::vector<MovableObject> objects;
  std::vector<Region> regions;
  std::array<double, 2> robot_start_m{0, 0};  ///< where the robot's base starts
  double robot_start_yaw_rad = 0.0;
  /// `robot_starts`: where the second, third, ... robot starts (the first
  /// starts at robot_start).
  std::vector<RobotStart> robot_starts;
};

/// The built-in yard: flat ground, a few boxes away from the start.
WorldDescription default_world();
/// Loads a world file. Throws std::runtime_error "file:line: key: message".
WorldDescription load_world_description(const std::string& path);
WorldDescription parse_world_description(const std::string& text, const std::string& file);

}  // namespace rise::sim
