#pragma once

// The semantic net of the seed paper (section 3, after Grau 1997 and
// Nüchter et al. 2003): the entities segment() found — floor, ceiling,
// walls, doors, stairs, obstacles — as nodes, and the spatial relations
// between them computed from their geometry: parallel, orthogonal, above,
// under, equal height, available inside (a door inside its wall, the stairs
// inside the building).

#include <Eigen/Core>

#include <string>
#include <vector>

#include "semantic/segmentation.hpp"

namespace rise::semantic {

/// Step: one tread of a staircase (index: the stairs'; its name says which
/// step), as the paper's stairs model has each step above and parallel to
/// the one before.
enum class EntityKind { Floor, Ceiling, Wall, Door, Stairs, Step, Obstacle };
enum class Relation { Parallel, Orthogonal, Above, Under, EqualHeight, Inside };

/// "floor", "ceiling", "wall", "door", "stairs", "step", "obstacle"; "parallel", "orthogonal", "above",
/// "under", "equal_height", "inside".
const char* to_string(EntityKind kind);
const char* to_string(Relation relation);

struct Entity {
  int id = 0;                  ///< index in SemanticNet::entities()
  EntityKind kind = EntityKind::Wall;
  std::string name;            ///< "wall_0", "door_1", ...
  int index = 0;               ///< into the Segmentation's vector of its kind
  Eigen::Vector3d position_m{0, 0, 0};  ///< centre, world frame
  Eigen::Vector3d size_m{0, 0, 0};      ///< along yaw, across, up
  double yaw_rad = 0.0;
};

/// `from` stands in `relation` to `to`: (door_0, inside, wall_2),
/// (ceiling, above, floor).
struct Link {
  int from = 0;
  Relation relation = Relation::Parallel;
  int to = 0;
};

struct SemanticNetSettings {
  double angle_tolerance_rad = 2.0 * 3.14159265358979 / 180.0;  ///< parallel / orthogonal
  double height_tolerance_m = 0.03;                              ///< equal height, above / under
  double inside_margin_m = 0.05;
};

class SemanticNet {
 public:
  explicit SemanticNet(Segmentation segmentation, const SemanticNetSettings& settings = {});

  const Segmentation& segmentation() const { return seg_; }
  const std::vector<Entity>& entities() const { return entities_; }
  const std::vector<Link>& links() const { return links_; }
  const Entity& entity(int id) const { return entities_.at(static_cast<std::size_t>(id)); }
  /// The ids of the entities of `kind`, in the Segmentation's order.
  std::vector<int> of_kind(EntityKind kind) const;
  /// The ids b with (id, relation, b).
  std::vector<int> related(int id, Relation relation) const;
  bool holds(int from, Relation relation, int to) const;

 private:
  Segmentation seg_;
  std::vector<Entity> entities_;
  std::vector<Link> links_;
};

/// The entities (kind, name, position, size, yaw and per kind: steps,
/// riser, tread, width, landing; door width, height, lintel, panel; wall
/// thickness, openings), the floor and ceiling heights and the relations,
/// as a JSON document (UTF-8, 2-space indent).
std::string to_json(const SemanticNet& net);

}  // namespace rise::semantic
