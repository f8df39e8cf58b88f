#pragma once

// The Training Builder's API (behind the same token as every route; the
// four routes are instructor/design_routes.hpp's):
//   GET  /api/builder/trainings            the training and task files of --designs DIR
//   GET  /api/builder/training/NAME        its text, version, graph (or the loader's errors)
//   POST /api/builder/training/NAME/check  {graph} → the YAML it would save and its errors
//   POST /api/builder/training/NAME        {version, graph} → saved (new version); 409 when
//                                          the file changed on disk since `version`; 422 with
//                                          the errors when it would not load
// (instructor/design_files.hpp, instructor/training_builder.hpp).

#include <string>

namespace httplib {
class Server;
}

namespace rise::instructor {

/// Adds the routes; `designs_dir` "" answers 503 on each.
void add_builder_routes(httplib::Server& http, const std::string& designs_dir);

}  // namespace rise::instructor
