// rise-instructor: the instructor station. Lists trainees, injects and
// clears faults, runs fault scenarios and starts/stops tasks over signed
// LCM commands (msgs/command_auth.hpp), prints the trainer's reports.

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "cli/command_line.hpp"
#include "instructor/app/instructor_commands.hpp"
#include "instructor/app/serve_command.hpp"

int main(int argc, char** argv) {
  CLI::App app{"rise-instructor: the instructor station (signed fault and training commands over LCM)"};
  app.require_subcommand(1);
  rise::instructor::add_common_options(app);
  rise::instructor::add_keygen_command(app);
  rise::instructor::add_list_command(app);
  rise::instructor::add_inject_command(app);
  rise::instructor::add_clear_command(app);
  rise::instructor::add_scenario_command(app);
  rise::instructor::add_task_command(app);
  rise::instructor::add_report_command(app);
  rise::instructor::add_serve_command(app);
  if (const auto code = rise::cli::parse_command_line(app, "rise-instructor", argc, argv)) return *code;
  return 0;
}
