# Every dependency is a Debian package (see .ci/deps). Workarounds for the packages'
# own CMake files are explained in ../shared/design/STACK.md.

find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(TBB REQUIRED)
find_package(embree 3.13 REQUIRED CONFIG)          # imported target: embree
find_package(OpenMesh REQUIRED CONFIG)              # no version file: ask for none
# glTF assets: meshoptimizer's codecs for EXT_meshopt_compression (Debian's config has only a
# "None" configuration, which CMake falls back to), nlohmann's JSON (header-only, build only).
find_package(meshoptimizer 0.18 REQUIRED CONFIG)
find_package(nlohmann_json 3.10 REQUIRED CONFIG)

include(${CMAKE_CURRENT_LIST_DIR}/prtsubImports.cmake)

if(PRTSUB_BUILD_TESTS)
  find_package(GTest REQUIRED)
  find_package(TinyGLTF REQUIRED CONFIG)  # an independent glTF reader for the tests
endif()
