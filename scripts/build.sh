#!/usr/bin/env bash
# Configures and builds occswitch into build/ (or $OCC_BUILD_DIR). Extra args go to cmake configure.
set -euo pipefail
source "$(dirname "$0")/lib.sh"  # --version
occ_help_first "$@"  # before anything is installed or built
cd "$(dirname "$0")/.."
BUILD_DIR=${OCC_BUILD_DIR:-build}
if [ ! -f "$BUILD_DIR/CMakeCache.txt" ] || [ $# -gt 0 ]; then
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo "$@" >/dev/null
fi
cmake --build "$BUILD_DIR" -j"$(nproc)"
