# libmodbus (Debian libmodbus-dev) ships only a pkg-config file: make an
# imported target PkgConfig::libmodbus from it.
find_package(PkgConfig REQUIRED)
pkg_check_modules(libmodbus REQUIRED IMPORTED_TARGET libmodbus)
