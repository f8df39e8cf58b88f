#pragma once

// rise-instructor's subcommands. Each add_*_command registers one
// subcommand with its options and its callback on `app`; a command that
// fails throws CLI::RuntimeError(exit code) (CLI11_PARSE returns it), so a
// new subcommand (e.g. the web console's `serve`, serve_command.hpp) is one
// add_* line in rise_instructor_main.cpp.

#include <CLI/CLI.hpp>

#include <string>

#include "msgs/channels.hpp"

namespace rise::instructor {

/// Options every subcommand shares, given before or after the subcommand.
struct CommonOptions {
  std::string lcm_url = rise::msgs::kDefaultLcmUrl;
  std::string key_file;        ///< --instructor-key, else env RISE_INSTRUCTOR_KEY
  std::string issuer = "instructor";
  std::string log_level = "info";
};
/// The process's common options (filled by parsing).
CommonOptions& common_options();
/// --lcm, --instructor-key, --issuer, --log-level on `app` (fallthrough).
void add_common_options(CLI::App& app);

void add_keygen_command(CLI::App& app);    ///< keygen FILE
void add_list_command(CLI::App& app);      ///< list [--wait S]
void add_inject_command(CLI::App& app);    ///< inject --trainee ID KIND TARGET [--value --rate --duration --id --seed]
void add_clear_command(CLI::App& app);     ///< clear --trainee ID [FAULT]
void add_scenario_command(CLI::App& app);  ///< scenario FILE|--task TASK --trainee ID [--seed --duration]
void add_task_command(CLI::App& app);      ///< task start|stop|restart --trainee ID [--task NAME]
void add_report_command(CLI::App& app);    ///< report --trainee ID --reports-dir DIR [--html]

}  // namespace rise::instructor
