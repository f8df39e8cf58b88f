#pragma once

#include <string>

namespace rise::panels {

/// Finds a file shipped in the source tree (definitions, scripts, robots) by
/// its path relative to the repo root: as given (from the working directory),
/// then under $RISE_ROOT, then the installed copy (<bin>/../share/rise, from
/// `cmake --install`), then the source tree this binary was built from.
/// Returns the path as given if none has it.
std::string find_data_file(const std::string& relative);

}  // namespace rise::panels
