#!/usr/bin/env bash
# Builds one of bench/'s C++ programs against a build's libraries and runs it (each says what it
# measures at the top of its .cpp). usage: bash bench/cpp.sh BUILD_DIR NAME [ARGS...]
set -euo pipefail
build=$(cd "$1" && pwd) name=$2
shift 2
here=$(cd "$(dirname "$0")" && pwd)
g++ -std=c++17 -O2 -flto=auto -I"$build/include" -I/usr/include/eigen3 "$here/$name.cpp" -o "$build/$name" \
  "$build/libprtsub_prt.a" "$build/libprtsub_subdiv.a" \
  -lembree3 -ltbb -lcholmod -lmeshoptimizer -lxxhash -losdCPU -lOpenMeshCore -lOpenMeshTools -lpthread
"$build/$name" "$@"
