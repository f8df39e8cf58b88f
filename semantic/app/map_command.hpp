#pragma once

// `rise-semantic map SCANS... -o DIR`: the pipeline end to end (map_pipeline.hpp):
// reads the scans (PCD + .pose, .3d + .pose, PLY, XYZ), registers them by 6D
// SLAM with a progress bar on stderr, levels and segments the merged map and
// writes DIR/world.yaml, map.png, world.sdf, mesh.obj, map.pcd, poses.txt and
// entities.json; prints what it found (scans, points, loops, entities with
// their sizes, per-stage timings). Bad input: the message and exit code 2.

#include <CLI/CLI.hpp>

namespace rise::semantic {

/// Adds the `map` subcommand to `app`; it runs when parsed.
void add_map_command(CLI::App& app);

}  // namespace rise::semantic
