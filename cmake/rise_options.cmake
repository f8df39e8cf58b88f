# One place for the project's compile options; never global flags.
function(rise_target_options target)
  target_compile_features(${target} PUBLIC cxx_std_20)
  set_target_properties(${target} PROPERTIES CXX_EXTENSIONS OFF)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wconversion -pedantic)
  if(RISE_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
  # The repo root is the include root: #include "sim/world.hpp".
  target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}>)
endfunction()
