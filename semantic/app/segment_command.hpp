#pragma once

// `rise-semantic segment CLOUD [--json] [--level] [--out-dir DIR]`: the
// entities found in one registered cloud (world frame, z up), printed as a
// summary or as JSON (semantic::to_json); with --out-dir also the world
// file, PNG map, SDF world and OBJ mesh made from them.

#include <CLI/CLI.hpp>

namespace rise::semantic {

/// Adds the `segment` subcommand to `app`; it runs when parsed.
void add_segment_command(CLI::App& app);

}  // namespace rise::semantic
