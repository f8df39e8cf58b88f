#include <catch2/catch.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "semantic/semantic_net.hpp"
#include "tests/semantic/building_cloud.hpp"

using namespace rise::semantic;
using namespace rise::semantic::testing;

namespace {
int find(const SemanticNet& net, EntityKind kind, const Eigen::Vector2d& near) {
  int best = -1;
  for (const int id : net.of_kind(kind))
    if (best < 0 || (net.entity(id).position_m.head<2>() - near).norm() < (net.entity(best).position_m.head<2>() - near).norm())
      best = id;
  return best;
}
}  // namespace

TEST_CASE("the building's semantic net relates walls, doors, stairs, floor and ceiling", "[semantic]") {
  const SemanticNet net(building_segmentation());
  const auto floors = net.of_kind(EntityKind::Floor), ceilings = net.of_kind(EntityKind::Ceiling);
  REQUIRE(floors.size() == 1);
  REQUIRE(ceilings.size() == 1);
  const int floor = floors[0], ceiling = ceilings[0];
  CHECK(net.holds(ceiling, Relation::Above, floor));
  CHECK(net.holds(floor, Relation::Under, ceiling));
  CHECK(net.holds(floor, Relation::Parallel, ceiling));
  CHECK_FALSE(net.holds(floor, Relation::Above, ceiling));

  const int south = find(net, EntityKind::Wall, {2.5, -3.0});    // wall_south
  const int north = find(net, EntityKind::Wall, {2.5, 5.5});     // wall_north
  const int west = find(net, EntityKind::Wall, {-4.0, 1.0});     // wall_west
  CHECK(net.holds(south, Relation::Parallel, north));
  CHECK(net.holds(south, Relation::Orthogonal, west));
  CHECK_FALSE(net.holds(south, Relation::Orthogonal, north));
  CHECK(net.holds(south, Relation::EqualHeight, north));
  CHECK(net.holds(south, Relation::Above, floor));
  CHECK(net.holds(south, Relation::Under, ceiling));

  // Doors inside their walls: the doorway in the corridor wall, the hinged
  // door between the two halves of the wall between rooms A and B.
  const int doorway = find(net, EntityKind::Door, {6.45, 3.0});
  const int door_ab = find(net, EntityKind::Door, {3.0, 0.0});
  REQUIRE(doorway != door_ab);
  CHECK(net.holds(doorway, Relation::Inside, find(net, EntityKind::Wall, {4.0, 3.0})));
  CHECK(net.holds(door_ab, Relation::Inside, find(net, EntityKind::Wall, {3.0, 1.5})));
  CHECK(net.holds(door_ab, Relation::Inside, find(net, EntityKind::Wall, {3.0, -1.5})));
  CHECK_FALSE(net.holds(door_ab, Relation::Inside, south));
  CHECK(net.holds(door_ab, Relation::Orthogonal, doorway));

  // The stairs inside the building, parallel to the corridor, under the ceiling.
  const auto stairs = net.of_kind(EntityKind::Stairs);
  REQUIRE(stairs.size() == 1);
  CHECK(net.holds(stairs[0], Relation::Inside, floor));
  CHECK(net.holds(stairs[0], Relation::Parallel, north));
  CHECK(net.holds(stairs[0], Relation::Under, ceiling));
  // Its steps: each above and parallel to the one before, inside the stairs.
  const auto steps = net.of_kind(EntityKind::Step);
  REQUIRE(steps.size() == 6);
  for (std::size_t k = 1; k < steps.size(); ++k) {
    CHECK(net.holds(steps[k], Relation::Above, steps[k - 1]));
    CHECK(net.holds(steps[k - 1], Relation::Under, steps[k]));
    CHECK(net.holds(steps[k], Relation::Parallel, steps[k - 1]));
    CHECK_FALSE(net.holds(steps[k - 1], Relation::Above, steps[k]));
    CHECK(net.entity(steps[k]).position_m.z() - net.entity(steps[k - 1]).position_m.z() == Approx(0.17).margin(0.01));
  }
  for (const int s : steps) CHECK(net.holds(s, Relation::Inside, stairs[0]));
  CHECK(net.entity(steps[0]).name == "stairs_0_step_1");
  const auto inside_floor = net.related(stairs[0], Relation::Inside);
  CHECK(std::find(inside_floor.begin(), inside_floor.end(), floor) != inside_floor.end());
}

TEST_CASE("the semantic net's JSON is valid and carries steps, riser, tread and door sizes", "[semantic]") {
  const SemanticNet net(building_segmentation());
  const std::string json = to_json(net);
  const auto path = std::filesystem::temp_directory_path() / "rise_semantic_net_test.json";
  {
    std::ofstream(path) << json;
  }
  // Python's json module parses it and reads the fields back.
  const std::string cmd = "/usr/bin/python3 -c \"import json,sys; d=json.load(open(sys.argv[1])); "
                          "k=[e['kind'] for e in d['entities']]; s=[e for e in d['entities'] if e['kind']=='stairs'][0]; "
                          "dr=[e for e in d['entities'] if e['kind']=='door']; "
                          "assert k.count('wall')>=8 and k.count('door')==2 and k.count('floor')==1, k; "
                          "assert s['steps']==6 and abs(s['riser_m']-0.17)<0.01 and abs(s['tread_m']-0.28)<0.01, s; "
                          "assert all(1.8<e['height_m']<2.1 and 0.8<e['width_m']<1.0 for e in dr), dr; "
                          "assert abs(d['ceiling_height_m']-2.6)<0.02 and len(d['relations'])>0\" " +
                          path.string();
  CHECK(std::system(cmd.c_str()) == 0);
  std::filesystem::remove(path);
}
