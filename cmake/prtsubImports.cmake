# The libraries prtsub's static libraries link privately, as imported targets. Debian ships
# them without usable CMake files (each workaround is explained beside it). The
# build includes this file, and so does the installed package config: a consumer linking the
# static libraries needs the same targets.
include_guard(GLOBAL)

# A shared library Debian ships without a usable CMake config: find its header and library and
# wrap them in an imported target.
function(prtsub_import_library target header library)
  cmake_parse_arguments(ARG "" "" "PATH_SUFFIXES" ${ARGN})
  string(MAKE_C_IDENTIFIER "${target}" id)
  find_path(${id}_INCLUDE_DIR ${header} PATH_SUFFIXES ${ARG_PATH_SUFFIXES} REQUIRED)
  find_library(${id}_LIBRARY ${library} REQUIRED)
  if(NOT TARGET ${target})
    add_library(${target} SHARED IMPORTED)
    set_target_properties(${target} PROPERTIES
      IMPORTED_LOCATION "${${id}_LIBRARY}"
      INTERFACE_INCLUDE_DIRECTORIES "${${id}_INCLUDE_DIR}")
  endif()
endfunction()

# OpenSubdiv: Debian's config names a static libosdCPU.a that is not shipped, so the
# package's config cannot be used. Far needs only the shared osdCPU library.
prtsub_import_library(OpenSubdiv::osdCPU opensubdiv/far/topologyRefinerFactory.h osdCPU)

# OpenImageIO: Debian's config cannot be used as it is. It lists /usr/include/opencv4 (there
# only with OpenCV's dev package), and its targets name /usr/bin/iconvert and PyImath, which
# other packages ship. Pkg-config describes the library itself, so use that.
find_package(PkgConfig REQUIRED)
pkg_check_modules(OIIO REQUIRED IMPORTED_TARGET OpenImageIO)
if(NOT TARGET OpenImageIO::OpenImageIO)
  add_library(OpenImageIO::OpenImageIO INTERFACE IMPORTED)
  target_link_libraries(OpenImageIO::OpenImageIO INTERFACE PkgConfig::OIIO)
endif()

# xxHash (the batch's content keys): Debian ships pkg-config's file and no CMake one.
pkg_check_modules(XXHASH REQUIRED IMPORTED_TARGET libxxhash)

# CHOLMOD (SuiteSparse) for the least-squares fit's factorisation: no CMake or pkg-config file
# in Debian. Its supernodal factorisation runs on BLAS: .ci/deps installs OpenBLAS, ~3x faster
# than Debian's reference BLAS (STACK.md).
prtsub_import_library(SuiteSparse::CHOLMOD cholmod.h cholmod PATH_SUFFIXES suitesparse)
