// rise-instructor: the instructor station's tools.

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "instructor/app/serve_command.hpp"

int main(int argc, char** argv) {
  CLI::App app{"rise-instructor: the instructor station"};
  app.require_subcommand(1);
  rise::instructor::add_serve_command(app);
  try {
    CLI11_PARSE(app, argc, argv);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  return 0;
}
