# cmake -P script (cli/CMakeLists.txt runs it at every build): writes OUTPUT,
# the definition of rise::cli::version(), from `git describe --tags --always
# --dirty` of SOURCE_DIR, or PROJECT_VERSION alone where SOURCE_DIR is not a
# git checkout (a tarball, or no git). OUTPUT is rewritten only when its
# text changes, so a build at the same commit recompiles nothing.
set(describe "")
# Only SOURCE_DIR's own checkout (.git is a folder, or a file in a worktree):
# a tarball unpacked inside another repository must not take its commit.
if(GIT_EXECUTABLE AND EXISTS "${SOURCE_DIR}/.git")
  execute_process(
    COMMAND "${GIT_EXECUTABLE}" -C "${SOURCE_DIR}" describe --tags --always --dirty
    RESULT_VARIABLE rc
    OUTPUT_VARIABLE describe
    OUTPUT_STRIP_TRAILING_WHITESPACE
    ERROR_QUIET)
  if(NOT rc EQUAL 0)
    set(describe "")
  endif()
endif()
if(describe)
  set(text "${PROJECT_VERSION} (${describe})")
else()
  set(text "${PROJECT_VERSION}")
endif()

set(content "// Written by cmake/rise_version.cmake at build time.\n#include \"cli/version.hpp\"\n\nnamespace rise::cli {\n\nconst char* version() { return \"${text}\"; }\n\n}  // namespace rise::cli\n")
set(old "")
if(EXISTS "${OUTPUT}")
  file(READ "${OUTPUT}" old)
endif()
if(NOT old STREQUAL content)
  file(WRITE "${OUTPUT}" "${content}")
endif()
