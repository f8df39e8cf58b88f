// rise-semantic: the semantic engine's command line. Each subcommand lives in
// its own semantic/app/<name>_command.{hpp,cpp} and adds itself with one
// add_<name>_command(app) line below.

#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "cli/command_line.hpp"
#include "semantic/app/map_command.hpp"
#include "semantic/app/register_command.hpp"
#include "semantic/app/segment_command.hpp"

int main(int argc, char** argv) {
  // Results go to stdout; the log goes to stderr so that both can be piped.
  spdlog::set_default_logger(spdlog::stderr_color_mt("rise-semantic"));

  CLI::App app{"rise-semantic: scans -> registered map -> walls, doors, floor, stairs -> a world file"};
  app.require_subcommand(1);
  app.fallthrough();  // -q also after the subcommand
  bool quiet = false;
  app.add_flag("-q,--quiet", quiet, "log warnings and errors only");
  app.parse_complete_callback([&quiet]() {
    if (quiet) spdlog::set_level(spdlog::level::warn);
  });

  rise::semantic::add_register_command(app);
  rise::semantic::add_segment_command(app);
  rise::semantic::add_map_command(app);

  if (const auto code = rise::cli::parse_command_line(app, "rise-semantic", argc, argv)) return *code;
  return 0;
}
