#pragma once

// The Environment Builder's side of the server (/world_builder.html): the
// world files of `rise-instructor serve --worlds DIR` (sim/README.md), a
// world as the page edits it (JSON in the file's own keys and units), turned
// into the YAML that would be saved (sim/world_writer.hpp, keeping the
// comments of the file on disk) and loaded by the loader rise-sim uses,
// whose error shows with its line and key. Saved through DesignFolder
// (atomic, versioned, 409 when the file changed on disk). Routes (behind the
// token):
//   GET  /api/builder/worlds              the .yaml files of DIR: [{file, name | error}]
//   GET  /api/builder/world/NAME          its text, version, world (or load_error), view (/api/world's form)
//   POST /api/builder/world/NAME/check    {world} → {yaml, ok, errors: [{file, line, key, message}], view}
//   POST /api/builder/world/NAME          {version, world} → saved (new version); 409 when the file
//                                         changed since `version`; 422 with the errors when it would not load

#include <json/json.h>

#include <optional>
#include <string>
#include <vector>

#include "instructor/training_builder.hpp"
#include "sim/world_description.hpp"

namespace httplib {
class Server;
}

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
  Json::Value view;                  ///< the loaded world as /api/world draws it (null with errors)
};

/// Writes `world` as it would be saved at `path` (with the comments of
/// `disk_text`, the file it replaces) and loads it with the loader of rise-sim.
WorldCheck check_world(const sim::WorldDescription& world, const std::string& path, const std::string& disk_text);

/// Adds the routes; `worlds_dir` "" answers 503 on each.
void add_world_builder_routes(httplib::Server& http, const std::string& worlds_dir);

}  // namespace rise::instructor
