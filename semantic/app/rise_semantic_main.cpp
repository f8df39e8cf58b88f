// rise-semantic: scans → registered map → entities → world file. (Minimal
// front door for the segment subcommand; the full program adds map and
// register.)

#include <CLI/CLI.hpp>

#include "semantic/app/segment_command.hpp"

int main(int argc, char** argv) {
  CLI::App app{"rise-semantic: point clouds to semantic entities and simulator worlds"};
  rise::semantic::add_segment_command(app);
  app.require_subcommand(1);
  CLI11_PARSE(app, argc, argv);
  return 0;
}
