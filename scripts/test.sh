#!/usr/bin/env bash
# Installs what is missing, builds, and runs every test (CTest labels unit, gl, integration).
#   scripts/test.sh              all tests
#   scripts/test.sh -L unit      only one label (any ctest arguments are passed through)
#   scripts/test.sh --sanitize   ASan+UBSan build in build-asan/, then the suite
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh

if [ "${1:-}" = "--sanitize" ]; then
  shift
  export OCC_BUILD_DIR=build-asan
  export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
  export LSAN_OPTIONS=suppressions=$PWD/tests/lsan.supp
  export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
  scripts/build.sh -DOCC_SANITIZE=ON
else
  scripts/build.sh
fi
BUILD_DIR=${OCC_BUILD_DIR:-build}

# One rasteriser thread per process: with several processes on 2 cores this is as fast or faster.
export LP_NUM_THREADS=${LP_NUM_THREADS:-1}
ctest --test-dir "$BUILD_DIR" --output-on-failure --timeout 600 "$@"
