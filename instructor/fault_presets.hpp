#pragma once

// The web console's fault buttons: each a FaultCommand's fields
// (hil/input_fault.hpp, hil/fault_injector.hpp, the sim's physics faults)
// under a name the page shows.

#include <string>
#include <vector>

namespace rise::instructor {

/// One fault button of the console.
struct FaultPreset {
  std::string id;      ///< the fault instance's name (FaultCommand.fault_id)
  std::string label;
  std::string kind;
  std::string target;
  double value = 0.0;
  double rate = 0.0;
  double duration_s = 0.0;  ///< 0 = until cleared
};

/// The console's fault buttons for the reference console and robots.
const std::vector<FaultPreset>& default_fault_presets();

/// The preset named `id` among default_fault_presets(); nullptr if none.
const FaultPreset* find_fault_preset(const std::string& id);

}  // namespace rise::instructor
