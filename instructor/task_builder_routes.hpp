#pragma once

// The Task Builder's API (behind the same token as every route; the files of
// `rise-instructor serve --designs DIR`, where trainings and tasks live together):
//   GET  /api/builder/tasks              the task files, and the event kinds the executor scores
//   GET  /api/builder/task/NAME          its text, version, task, world (drawn top-down), check
//   POST /api/builder/task/NAME/check    {task} → the YAML it would save and its errors (line, key)
//   POST /api/builder/task/NAME          {version, task} → saved (new version); 409 when the file
//                                        changed on disk since `version` ("" : must be new); 422
//                                        with the errors when it would not load
//   POST /api/builder/task/NAME/try      runs the saved file in a sandbox (instructor/sandbox.hpp):
//                                        rise-sim + rise-trainer run-task on station
//                                        "sandbox-<server pid>" (apart from another server's on
//                                        the same LCM); the user drives with the virtual panel
//                                        page the reply names (panel.html?id=STATION); each
//                                        try's logs and report in its own folder of
//                                        $TMPDIR/rise-task-builder-<server pid>/try-N
//   GET  /api/builder/try                the sandbox's state and, once the task ended, its report
//   GET  /api/builder/try/report.html    the report as rise-trainer wrote it
//   POST /api/builder/try/stop           stops it (the trainer writes the report: interrupted)
// (instructor/task_builder.hpp, instructor/design_files.hpp).

#include <string>

namespace httplib {
class Server;
}

namespace rise::instructor {

/// Adds the routes; `designs_dir` "" answers 503 on each. The sandbox starts
/// the programs of `bin_dir` on `lcm_url` (the server's).
void add_task_builder_routes(httplib::Server& http, const std::string& designs_dir, const std::string& bin_dir,
                             const std::string& lcm_url);

}  // namespace rise::instructor
