#!/usr/bin/env bash
# Builds bench/variance_calibration.cpp and runs it on one scene (see the top of the .cpp).
# usage: bash bench/variance_calibration.sh BUILD_DIR SCENE [R] [REF]
exec bash "$(dirname "$0")/cpp.sh" "$1" variance_calibration "${@:2}"
