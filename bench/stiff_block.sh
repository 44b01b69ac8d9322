#!/usr/bin/env bash
# Builds bench/stiff_block.cpp and runs it on one scene (see the top of the .cpp).
# usage: bash bench/stiff_block.sh BUILD_DIR SCENE "THRESHOLDS" [REPEAT]
exec bash "$(dirname "$0")/cpp.sh" "$1" stiff_block "${@:2}"
