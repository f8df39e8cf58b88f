#pragma once

// The environment: a ground plane and static box obstacles (the world file
// the semantic engine will grow into; see sim/README.md).

#include <array>
#include <string>
#include <vector>

namespace rise::sim {

struct BoxObstacle {
  std::string name;
  std::array<double, 3> center_m{};  ///< world frame, z up
  std::array<double, 3> size_m{1, 1, 1};
  double yaw_rad = 0.0;
};

struct WorldDescription {
  std::string name = "yard";
  std::string file;
  double ground_friction = 1.0;
  std::vector<BoxObstacle> boxes;
};

/// The built-in yard: flat ground, a few boxes away from the start.
WorldDescription default_world();
/// Loads a world file. Throws std::runtime_error "file:line: key: message".
WorldDescription load_world_description(const std::string& path);
WorldDescription parse_world_description(const std::string& text, const std::string& file);

}  // namespace rise::sim
