#pragma once

// The Robot Builder's API (behind the same token as every route):
//   GET  /api/builder/robots              the robot files of --robots DIR
//   GET  /api/builder/robot/NAME          its text, version, values by path, the 3D view (or the loader's errors)
//   POST /api/builder/robot/NAME/check    {edits: [{path, value}]} → the YAML it would save, its errors, the view
//   POST /api/builder/robot/NAME          {version, edits} → saved (new version); 409 when the file changed on
//                                         disk since `version`; 422 with the errors when rise-sim would refuse it
//   POST /api/builder/robot/NAME/drive    test drive: rise-sim with the saved file in the sandbox world on
//                                         the sandbox station → {station, panel (the virtual panel's page)}
//   POST /api/builder/drive/stop          ends it;  GET /api/builder/drive: where it is
// (instructor/robot_builder.hpp, instructor/design_files.hpp, instructor/sandbox.hpp).

#include <string>

namespace httplib {
class Server;
}

namespace rise::instructor {

struct RobotBuilderSettings {
  std::string robots_dir;   ///< "" → the routes answer 503
  std::string world_file;   ///< the test drive's world ("" → none: rise-sim's built-in yard)
  std::string lcm_url;      ///< the LCM the server's virtual panels publish on
  std::string station = "robot_sandbox";  ///< the test drive's trainee id
};

void add_robot_builder_routes(httplib::Server& http, const RobotBuilderSettings& settings);

}  // namespace rise::instructor
