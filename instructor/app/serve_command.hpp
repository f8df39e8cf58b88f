#pragma once

#include <CLI/CLI.hpp>

namespace rise::instructor {

/// Adds `serve` (the web console and the virtual panels) to rise-instructor.
void add_serve_command(CLI::App& app);

}  // namespace rise::instructor
