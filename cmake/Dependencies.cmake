# Every dependency is a Debian package (see .ci/deps). Workarounds for the packages'
# own CMake files are explained in ../shared/design/STACK.md.

find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(TBB REQUIRED)
find_package(embree 3.13 REQUIRED CONFIG)          # imported target: embree
find_package(OpenMesh REQUIRED CONFIG)              # no version file: ask for none

# OpenSubdiv: Debian's config names a static libosdCPU.a that is not shipped, so the
# package's config cannot be used. Far needs only the shared osdCPU library.
find_path(OPENSUBDIV_INCLUDE_DIR opensubdiv/far/topologyRefinerFactory.h REQUIRED)
find_library(OPENSUBDIV_CPU_LIBRARY osdCPU REQUIRED)
if(NOT TARGET OpenSubdiv::osdCPU)
  add_library(OpenSubdiv::osdCPU SHARED IMPORTED)
  set_target_properties(OpenSubdiv::osdCPU PROPERTIES
    IMPORTED_LOCATION "${OPENSUBDIV_CPU_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${OPENSUBDIV_INCLUDE_DIR}")
endif()

# OpenImageIO: Debian's config cannot be used as it is. It lists /usr/include/opencv4 (there
# only with OpenCV's dev package), and its targets name /usr/bin/iconvert and PyImath, which
# other packages ship. Pkg-config describes the library itself, so use that.
find_package(PkgConfig REQUIRED)
pkg_check_modules(OIIO REQUIRED IMPORTED_TARGET OpenImageIO)
if(NOT TARGET OpenImageIO::OpenImageIO)
  add_library(OpenImageIO::OpenImageIO INTERFACE IMPORTED)
  target_link_libraries(OpenImageIO::OpenImageIO INTERFACE PkgConfig::OIIO)
endif()

# CHOLMOD (SuiteSparse) for the least-squares fit's factorisation: no CMake or pkg-config file
# in Debian, so find the header and the library. Its supernodal factorisation runs on BLAS:
# .ci/deps installs OpenBLAS, ~3x faster than Debian's reference BLAS (STACK.md).
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse REQUIRED)
find_library(CHOLMOD_LIBRARY cholmod REQUIRED)
if(NOT TARGET SuiteSparse::CHOLMOD)
  add_library(SuiteSparse::CHOLMOD SHARED IMPORTED)
  set_target_properties(SuiteSparse::CHOLMOD PROPERTIES
    IMPORTED_LOCATION "${CHOLMOD_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${CHOLMOD_INCLUDE_DIR}")
endif()

if(PRTSUB_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
