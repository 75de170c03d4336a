# hypre (Debian's libhypre-dev) ships no CMake package here and, on Debian 12,
# no pkg-config file: try pkg-config first, then look for it by hand.
find_package(PkgConfig QUIET)
if(PKG_CONFIG_FOUND)
  pkg_check_modules(PC_HYPRE QUIET hypre)
endif()
find_path(HYPRE_INCLUDE_DIR HYPRE_parcsr_ls.h
  HINTS ${PC_HYPRE_INCLUDE_DIRS} PATH_SUFFIXES hypre)
find_library(HYPRE_LIBRARY NAMES HYPRE HINTS ${PC_HYPRE_LIBRARY_DIRS})
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(HYPRE REQUIRED_VARS HYPRE_LIBRARY HYPRE_INCLUDE_DIR)
if(HYPRE_FOUND AND NOT TARGET HYPRE::HYPRE)
  add_library(HYPRE::HYPRE UNKNOWN IMPORTED)
  set_target_properties(HYPRE::HYPRE PROPERTIES
    IMPORTED_LOCATION "${HYPRE_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${HYPRE_INCLUDE_DIR}")
endif()
mark_as_advanced(HYPRE_INCLUDE_DIR HYPRE_LIBRARY)
