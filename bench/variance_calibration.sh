#!/usr/bin/env bash
# Builds bench/variance_calibration.cpp against a build's libraries and runs it on one scene
# (see the top of the .cpp). usage: bash bench/variance_calibration.sh BUILD_DIR SCENE [R] [REF]
set -euo pipefail
build=$(cd "$1" && pwd) scene=$2
shift 2
here=$(cd "$(dirname "$0")" && pwd)
exe=$build/variance_calibration
g++ -std=c++17 -O2 -flto=auto -I"$build/include" -I/usr/include/eigen3 "$here/variance_calibration.cpp" -o "$exe" \
  "$build/libprtsub_prt.a" "$build/libprtsub_subdiv.a" \
  -lembree3 -ltbb -lcholmod -lmeshoptimizer -lxxhash -losdCPU -lOpenMeshCore -lOpenMeshTools -lpthread
"$exe" "$scene" "$@"
