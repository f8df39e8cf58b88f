#pragma once

// The Environment Builder's side of the server (/world_builder.html): the
// world files of `rise-instructor serve --worlds DIR` (sim/README.md), a
// world as the page edits it (JSON in the file's own keys and units), turned
// into the YAML that would be saved (sim/world_writer.hpp, keeping the
// comments of the file on disk) and loaded by the loader rise-sim uses,
// whose error shows with its line and key. Saved through DesignFolder
// (atomic, versioned, 409 when the file changed on disk) by the routes of
// instructor/world_builder_routes.hpp. Pure.

#include <json/json.h>

#include <optional>
#include <string>
#include <vector>

#include "instructor/training_builder.hpp"
#include "sim/world_description.hpp"

namespace rise::instructor {

/// {world, ground_friction, robot_start: {xy_m, yaw_deg}, robot_starts, ceiling: null |
///  {height_m, thickness_m, min, max, follows_walls}, boxes, props, walls (with openings), doors,
///  stairs, objects, regions}: each entry with the file's keys (hinge, yaw_deg, open_deg_max, ...).
Json::Value world_model_json(const sim::WorldDescription& world);

/// The page's JSON (untrusted) as a world to write: values are taken as
/// they are (the loader names what is out of range, with its line and key);
/// nullopt with *error set ("doors[1].hinge: expected 2 numbers") for a
/// body of the wrong shape.
std::optional<sim::WorldDescription> world_model_from_json(const Json::Value& body, std::string* error);

struct WorldCheck {
  std::string yaml;                  ///< what would be saved
  std::vector<BuilderError> errors;  ///< empty: rise-sim --world would load it
  std::optional<sim::WorldDescription> loaded;  ///< the yaml as rise-sim loads it (none with errors)
};

/// Writes `world` as it would be saved at `path` (with the comments of
/// `disk_text`, the file it replaces) and loads it with the loader of rise-sim.
WorldCheck check_world(const sim::WorldDescription& world, const std::string& path, const std::string& disk_text);

}  // namespace rise::instructor
