#pragma once

// Any robot's URDF as a general tree of links and joints (`kind: urdf_tree`
// in the robot YAML): revolute, continuous, prismatic and fixed joints with
// their limits, effort, velocity and damping; each link's inertia and its
// collision and visual shapes (box, cylinder, sphere, or a mesh read through
// assimp: sim/mesh_file.hpp). Unlike sim/urdf_robot.hpp it fits no fixed
// model: the simulator builds one ODE body per group of links that fixed
// joints hold together.

#include <array>
#include <string>
#include <vector>

#include "sim/mesh_file.hpp"

namespace rise::sim {

/// A rigid transform: translation (m) and unit quaternion (w, x, y, z).
struct UrdfPose {
  std::array<double, 3> xyz_m{};
  std::array<double, 4> wxyz{1, 0, 0, 0};

  bool operator==(const UrdfPose&) const = default;
};

enum class UrdfShapeType { Box, Cylinder, Sphere, Mesh };

/// One collision or visual shape in its link's frame.
struct UrdfShape {
  UrdfShapeType type = UrdfShapeType::Box;
  /// Box: x, y, z; cylinder: radius, length (along z); sphere: radius.
  std::array<double, 3> size_m{};
  UrdfPose origin;
  std::string mesh_file;                 ///< mesh: the path as the URDF gives it
  std::array<double, 3> mesh_scale{1, 1, 1};
  TriangleMesh mesh;                     ///< mesh: scaled, in the shape's frame (empty if not loaded)

  bool operator==(const UrdfShape&) const = default;
};

struct UrdfLink {
  std::string name;
  double mass_kg = 0.0;  ///< 0: no inertial (allowed only on links that fixed joints hold)
  UrdfPose inertial_origin;
  std::array<double, 6> inertia_kgm2{};  ///< ixx, ixy, ixz, iyy, iyz, izz about the inertial origin
  std::vector<UrdfShape> collisions;
  std::vector<UrdfShape> visuals;
  std::array<double, 4> rgba{0.6, 0.6, 0.65, 1.0};  ///< the first visual's material colour, if any

  bool operator==(const UrdfLink&) const = default;
};

enum class UrdfJointType { Revolute, Continuous, Prismatic, Fixed };

struct UrdfJoint {
  std::string name;
  UrdfJointType type = UrdfJointType::Fixed;
  std::size_t parent = 0;  ///< link index
  std::size_t child = 0;   ///< link index
  UrdfPose origin;         ///< child frame in the parent frame at position 0
  std::array<double, 3> axis{1, 0, 0};  ///< unit, in the joint (child) frame
  double lower = 0.0, upper = 0.0;      ///< rad or m; revolute and prismatic only
  double effort = 0.0;                  ///< N·m or N; 0 = not given
  double velocity = 0.0;                ///< rad/s or m/s; 0 = not given
  double damping = 0.0;                 ///< N·m·s/rad or N·s/m
  double friction = 0.0;                ///< N·m or N (static)

  bool operator==(const UrdfJoint&) const = default;
};

/// The tree: links[0] is the root; joints[i] leads to links[i + 1], and a
/// joint's parent comes before its child.
struct UrdfTree {
  std::vector<UrdfLink> links;
  std::vector<UrdfJoint> joints;

  bool operator==(const UrdfTree&) const = default;
  /// The joint's index, or joints.size() for an unknown name.
  std::size_t joint_index(const std::string& name) const;
  std::size_t link_index(const std::string& name) const;
  /// The link whose body carries `link`: up the fixed joints to the root or
  /// to the first link that moves. joints[i] leads to links[i + 1].
  std::size_t body_link(std::size_t link) const;
};

constexpr std::size_t kMaxUrdfLinks = 256;

/// Reads the URDF at `path`; its meshes are read from files relative to the
/// URDF's folder (or `file://` absolute paths; `package://` is refused: there
/// is no ROS package path). Throws std::runtime_error with liburdfdom's or
/// the mesh reader's message, or for what the simulator cannot build: more
/// than kMaxUrdfLinks links, a moving link without mass, a mass or inertia
/// that is not finite and positive (definite), a zero axis, lower > upper,
/// a negative effort, velocity or damping, a shape of size <= 0. Not for the
/// cyclic path.
UrdfTree read_urdf_tree(const std::string& path);
/// The same from the URDF's text; meshes are read relative to `mesh_dir`
/// when load_meshes, else kept by name only (the fuzz target).
UrdfTree parse_urdf_tree(const std::string& xml, const std::string& mesh_dir, bool load_meshes);

}  // namespace rise::sim
