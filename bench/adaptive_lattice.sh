#!/usr/bin/env bash
# Builds bench/adaptive_lattice.cpp and runs it on one scene (see the top of the .cpp).
# usage: bash bench/adaptive_lattice.sh BUILD_DIR SCENE [ORDER] [VERTICES] [REF_LEVELS]
exec bash "$(dirname "$0")/cpp.sh" "$1" adaptive_lattice "${@:2}"
