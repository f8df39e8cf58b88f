# hidapi with its hidraw backend (Debian libhidapi-dev) ships only a
# pkg-config file: make an imported target PkgConfig::hidapi_hidraw from it.
find_package(PkgConfig REQUIRED)
pkg_check_modules(hidapi_hidraw REQUIRED IMPORTED_TARGET hidapi-hidraw)
# libusb 1.0 (Debian libusb-1.0-0-dev) likewise: PkgConfig::libusb, for
# UsbHotplug's arrival callbacks.
pkg_check_modules(libusb REQUIRED IMPORTED_TARGET libusb-1.0)
