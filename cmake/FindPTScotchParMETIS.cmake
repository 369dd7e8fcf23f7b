# Finds the ParMETIS interface of PT-Scotch (Debian: libscotchparmetis-dev,
# libptscotch-dev) and defines PTScotchParMETIS::PTScotchParMETIS.
#
# The 64-bit build is used (SCOTCH_Num = int64_t, the header under
# parmetis-int64/): graphs of 10^9 nodes have more than 2^31 edges. Its shared
# libraries have the same sonames as Debian's default 32-bit ones (the loader
# would pick those), so the static archives are linked (they are PIC).
find_path(PTSCOTCHPARMETIS_INCLUDE_DIR parmetis.h PATH_SUFFIXES parmetis-int64 NO_DEFAULT_PATH
          PATHS /usr/include /usr/local/include)
set(_ptsp_dirs /usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}/scotch-int64)
find_library(PTSCOTCHPARMETIS_LIBRARY libptscotchparmetisv3.a PATHS ${_ptsp_dirs} NO_DEFAULT_PATH)
find_library(PTSCOTCH_LIBRARY libptscotch.a PATHS ${_ptsp_dirs} NO_DEFAULT_PATH)
find_library(PTSCOTCH_SCOTCH_LIBRARY libscotch.a PATHS ${_ptsp_dirs} NO_DEFAULT_PATH)
find_library(PTSCOTCH_ERR_LIBRARY libptscotcherr.a PATHS ${_ptsp_dirs} NO_DEFAULT_PATH)
find_library(PTSCOTCH_Z_LIBRARY z)
find_library(PTSCOTCH_BZ2_LIBRARY bz2)
find_library(PTSCOTCH_LZMA_LIBRARY lzma)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(PTScotchParMETIS DEFAULT_MSG PTSCOTCHPARMETIS_INCLUDE_DIR PTSCOTCHPARMETIS_LIBRARY
                                  PTSCOTCH_LIBRARY PTSCOTCH_SCOTCH_LIBRARY PTSCOTCH_ERR_LIBRARY PTSCOTCH_Z_LIBRARY
                                  PTSCOTCH_BZ2_LIBRARY PTSCOTCH_LZMA_LIBRARY)
if(PTScotchParMETIS_FOUND AND NOT TARGET PTScotchParMETIS::PTScotchParMETIS)
  add_library(PTScotchParMETIS::PTScotchParMETIS INTERFACE IMPORTED)
  find_package(Threads REQUIRED)
  set_target_properties(PTScotchParMETIS::PTScotchParMETIS PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES "${PTSCOTCHPARMETIS_INCLUDE_DIR}"
    INTERFACE_LINK_LIBRARIES "${PTSCOTCHPARMETIS_LIBRARY};${PTSCOTCH_LIBRARY};${PTSCOTCH_SCOTCH_LIBRARY};${PTSCOTCH_ERR_LIBRARY};${PTSCOTCH_Z_LIBRARY};${PTSCOTCH_BZ2_LIBRARY};${PTSCOTCH_LZMA_LIBRARY};Threads::Threads;m")
endif()
mark_as_advanced(PTSCOTCHPARMETIS_INCLUDE_DIR PTSCOTCHPARMETIS_LIBRARY PTSCOTCH_LIBRARY PTSCOTCH_SCOTCH_LIBRARY
                 PTSCOTCH_ERR_LIBRARY PTSCOTCH_Z_LIBRARY PTSCOTCH_BZ2_LIBRARY PTSCOTCH_LZMA_LIBRARY)
