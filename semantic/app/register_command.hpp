#pragma once

// `rise-semantic register SOURCE TARGET`: ICP of one cloud onto another.

#include <CLI/CLI.hpp>

namespace rise::semantic {

/// Adds the `register` subcommand to `app`; it prints the 4x4 transform
/// that maps SOURCE onto TARGET (row-major, metres), then rmse_m,
/// iterations, inlier_ratio and converged, one per line.
void add_register_command(CLI::App& app);

}  // namespace rise::semantic
