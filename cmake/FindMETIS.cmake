# METIS ships no CMake package and, on most systems, no pkg-config file: try
# pkg-config first, then look for it by hand.
find_package(PkgConfig QUIET)
if(PKG_CONFIG_FOUND)
  pkg_check_modules(PC_METIS QUIET metis)
endif()
find_path(METIS_INCLUDE_DIR metis.h
  HINTS ${PC_METIS_INCLUDE_DIRS} PATH_SUFFIXES metis)
find_library(METIS_LIBRARY NAMES metis HINTS ${PC_METIS_LIBRARY_DIRS})
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(METIS REQUIRED_VARS METIS_LIBRARY METIS_INCLUDE_DIR)
if(METIS_FOUND AND NOT TARGET METIS::METIS)
  add_library(METIS::METIS UNKNOWN IMPORTED)
  set_target_properties(METIS::METIS PROPERTIES
    IMPORTED_LOCATION "${METIS_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${METIS_INCLUDE_DIR}")
endif()
mark_as_advanced(METIS_INCLUDE_DIR METIS_LIBRARY)
