# PCL from Debian (libpcl-dev 1.13) with the components the caller names in
# RISE_PCL_COMPONENTS. PCL's Findlibusb can end up with the bare name
# "usb-1.0" as the imported library's location (a pkg-config variable of the
# same name wins); give it the real file so that programs link.
find_package(PCL 1.13 REQUIRED COMPONENTS ${RISE_PCL_COMPONENTS})
if(TARGET libusb::libusb)
  get_target_property(rise_usb_location libusb::libusb IMPORTED_LOCATION)
  if(NOT IS_ABSOLUTE "${rise_usb_location}")
    find_library(RISE_LIBUSB_LIBRARY NAMES usb-1.0 REQUIRED)
    set_target_properties(libusb::libusb PROPERTIES IMPORTED_LOCATION "${RISE_LIBUSB_LIBRARY}")
  endif()
endif()
