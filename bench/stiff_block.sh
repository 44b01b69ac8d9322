#!/usr/bin/env bash
# Builds bench/stiff_block.cpp against a build's libraries and runs it on one scene (see the top
# of the .cpp). usage: bash bench/stiff_block.sh BUILD_DIR SCENE "THRESHOLDS" [REPEAT]
set -euo pipefail
build=$(cd "$1" && pwd) scene=$2
shift 2
here=$(cd "$(dirname "$0")" && pwd)
exe=$build/stiff_block
g++ -std=c++17 -O2 -I"$build/include" -I/usr/include/eigen3 "$here/stiff_block.cpp" -o "$exe" \
  "$build/libprtsub_prt.a" "$build/libprtsub_subdiv.a" \
  -lembree3 -ltbb -lcholmod -lmeshoptimizer -lxxhash -losdCPU -lOpenMeshCore -lOpenMeshTools -lpthread
"$exe" "$scene" "$@"
