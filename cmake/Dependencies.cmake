# Every dependency is a Debian package (see .ci/deps). Workarounds for the packages'
# own CMake files are explained in ../shared/design/STACK.md.

find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(TBB REQUIRED)
find_package(embree 3.13 REQUIRED CONFIG)          # imported target: embree
find_package(OpenMesh REQUIRED CONFIG)              # no version file: ask for none

include(${CMAKE_CURRENT_LIST_DIR}/prtsubImports.cmake)

if(PRTSUB_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
