# Finds DSDP 5 (Debian: libdsdp-dev), the SDP solver of the centralized
# relaxations (sdp, esdp, edm), and defines DSDP::DSDP.
find_path(DSDP_INCLUDE_DIR dsdp/dsdp5.h)
find_library(DSDP_LIBRARY dsdp)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(DSDP DEFAULT_MSG DSDP_LIBRARY DSDP_INCLUDE_DIR)
if(DSDP_FOUND AND NOT TARGET DSDP::DSDP)
  add_library(DSDP::DSDP UNKNOWN IMPORTED)
  set_target_properties(DSDP::DSDP PROPERTIES
    IMPORTED_LOCATION "${DSDP_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${DSDP_INCLUDE_DIR}")
endif()
mark_as_advanced(DSDP_INCLUDE_DIR DSDP_LIBRARY)
