# Debian's libode-dev ships only a pkg-config file; wrap it in the imported target ODE.
find_package(PkgConfig REQUIRED)
pkg_check_modules(RISE_ODE REQUIRED IMPORTED_TARGET ode)
add_library(ODE INTERFACE IMPORTED)
target_link_libraries(ODE INTERFACE PkgConfig::RISE_ODE)
# ode.pc says precision=dDOUBLE; the headers need the macro to pick double.
target_compile_definitions(ODE INTERFACE dDOUBLE)
