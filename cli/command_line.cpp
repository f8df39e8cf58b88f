#include "cli/command_line.hpp"

#include "cli/version.hpp"

namespace rise::cli {

std::optional<int> parse_command_line(CLI::App& app, const std::string& program, int argc, char** argv) {
  app.name(program);
  app.set_version_flag("--version", program + " " + version(), "print the program's version and exit");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11's own codes (105 for a validation error, 106, 107, ...) would
    // each mean "bad input"; a callback's RuntimeError carries its result.
    const int code = app.exit(e);
    if (code == 0 || e.get_name() == "RuntimeError") return code;
    return kBadInput;
  }
  return std::nullopt;
}

}  // namespace rise::cli
