#pragma once

// liburdfdom's parser behind the checks both URDF readers need (private to
// sim/urdf_robot.cpp and sim/urdf_tree.cpp).

#include <urdf_model/model.h>
#include <urdf_world/types.h>

#include <string>

namespace rise::sim {

/// urdf::parseURDF on `xml` with its console_bridge log captured (not
/// printed); text that is not whole UTF-8 is refused first. Throws
/// std::runtime_error "liburdfdom: <its errors>" for a model it refuses or
/// reads only in part, "no root link" without a root.
urdf::ModelInterfaceSharedPtr parse_urdf_model(const std::string& xml);

}  // namespace rise::sim
