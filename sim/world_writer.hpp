#pragma once

// A world as the YAML that load_world_description reads (sim/README.md):
// what the instructor's Environment Builder saves. One flow mapping per
// entry, in the model's order, each number the shortest that reads back to
// the same value (degrees too: yaw_deg × π/180 gives the same radians), so
// that load → write → load gives the same world
// (tests/sim/world_writer_test.cpp checks it for every shipped world and
// one rise-semantic writes). The comments of the file being overwritten are
// kept where their entry still exists: the block above an entry (or above
// a top-level key) and the comment at the end of its line. Pure.

#include <map>
#include <string>

#include "sim/world_description.hpp"

namespace rise::sim {

/// The comments of a world file, by what they stand beside: "walls" (a
/// top-level key), "entry:door_ab" (a named entry), "robot_starts[1]".
struct WorldComments {
  std::map<std::string, std::string> above;     ///< whole lines ("# ...\n", blank lines kept), verbatim
  std::map<std::string, std::string> trailing;  ///< the text after '#' at the end of the entry's lines
  std::string end;                              ///< the lines after the last entry
};

/// The comments of `text`; none when it is no YAML mapping (never throws).
WorldComments read_world_comments(const std::string& text);

/// The YAML text of `world` with `comments` where their keys and entries
/// are. Defaults a shipped file writes anyway (a wall's height and
/// thickness, a door's width ... break torque) are written; the rest only
/// when they differ from the loader's default. A ceiling whose min and max
/// are the walls' outline is written without them (it follows the walls).
std::string write_world(const WorldDescription& world, const WorldComments& comments = {});

/// Whether the ceiling's min and max are the walls' outline (what the loader
/// gives a ceiling written without them); false without ceiling or walls.
bool ceiling_follows_walls(const WorldDescription& world);
/// Sets the ceiling's min and max to the walls' outline (no-op without
/// ceiling or walls): after an edit of the walls, as the loader would.
void fit_ceiling_to_walls(WorldDescription& world);

/// The degrees write_world writes for `rad` (as a number): what an editor
/// shows, so that typing nothing changes nothing.
double degrees_as_written(double rad);

}  // namespace rise::sim
