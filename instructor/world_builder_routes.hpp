#pragma once

// The Environment Builder's routes (instructor/world_builder.hpp), behind the
// token like every route; the files read and saved through DesignFolder
// (atomic, versioned, 409 when the file changed on disk since the page read it):
//   GET  /api/builder/worlds              the .yaml files of DIR: [{file, name | error}]
//   GET  /api/builder/world/NAME          its text, version, world (or load_error), view (/api/world's form)
//   POST /api/builder/world/NAME/check    {world} → {yaml, ok, errors: [{file, line, key, message}], view}
//   POST /api/builder/world/NAME          {version, world} → saved (new version); 409 when the file
//                                         changed since `version`; 422 with the errors when it would not load

#include <string>

namespace httplib {
class Server;
}

namespace rise::instructor {

/// Adds the routes; `worlds_dir` "" answers 503 on each.
void add_world_builder_routes(httplib::Server& http, const std::string& worlds_dir);

}  // namespace rise::instructor
