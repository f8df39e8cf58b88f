# Debian's liblcm-dev (1.3.1) has no CMake config and its lcm.pc needs glib's
# .pc files, which the runtime does not; find the library and lcm-gen directly.
find_library(RISE_LCM_LIBRARY NAMES lcm REQUIRED)
find_path(RISE_LCM_INCLUDE_DIR NAMES lcm/lcm-cpp.hpp REQUIRED)
find_program(LCM_GEN_EXECUTABLE NAMES lcm-gen REQUIRED)
add_library(lcm UNKNOWN IMPORTED)
set_target_properties(lcm PROPERTIES
  IMPORTED_LOCATION "${RISE_LCM_LIBRARY}"
  INTERFACE_INCLUDE_DIRECTORIES "${RISE_LCM_INCLUDE_DIR}")
