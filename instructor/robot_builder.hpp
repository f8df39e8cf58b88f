#pragma once

// The Robot Builder's side of the server (/robot_builder.html): a robot file
// (sim/robots/*.yaml) as the page shows it — its values by path with their
// lines, and what the 3D view draws (links and joint axes from the URDF
// beside it, wheels or tracks, the laser's fan, the cameras) — and the page's
// edits (path → new value) applied in place in the file's text
// (sim/yaml_edit.hpp: every comment stays), then loaded by the loader
// rise-sim --robot uses, its errors each with line and key. The URDF is read,
// never written. Never throws on the page's input.

#include <json/json.h>

#include <optional>
#include <string>
#include <vector>

#include "instructor/training_builder.hpp"  // BuilderError
#include "sim/robot_description.hpp"
#include "sim/yaml_edit.hpp"

namespace rise::instructor {

/// The page's edits ([{path, value}], values as text; untrusted). nullopt
/// with *error set ("edits[2].value: expected a string") for a body of the
/// wrong shape.
std::optional<std::vector<sim::YamlEdit>> robot_edits_from_json(const Json::Value& edits, std::string* error);

struct RobotCheck {
  std::string yaml;                         ///< what would be saved ("" when an edit could not apply)
  std::vector<BuilderError> errors;         ///< empty: rise-sim --robot would load it
  std::optional<sim::RobotDescription> robot;  ///< loaded, when no errors
};

/// `text` (the file at `path`) with `edits` applied, loaded as rise-sim
/// loads `path` (its URDF resolved beside it).
RobotCheck check_robot(const std::string& text, const std::vector<sim::YamlEdit>& edits, const std::string& path);

/// {yaml, ok, errors: [{file, line, key, message}], scalars, robot (the 3D view's, when ok)}.
Json::Value robot_check_json(const RobotCheck& check);

/// What the 3D view draws of `robot`: web_json.hpp's robot_json (name,
/// chassis, cameras) with the URDF's links and joints for every kind (a
/// link without visual shapes drawn by its collision shapes), and kind,
/// wheels or tracks, laser, arm joints' limits.
Json::Value robot_view_json(const sim::RobotDescription& robot, const std::string& urdf_path);

/// [{path, value, line}] of the text (yaml_edit.hpp); [] for text that is not YAML.
Json::Value robot_scalars_json(const std::string& text);

/// The robot files of `dir` for the page's list: [{file, name, kind} or {file, error}].
Json::Value robot_files_json(const std::string& dir, const std::vector<std::string>& yaml_files);

}  // namespace rise::instructor
