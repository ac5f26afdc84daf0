#!/usr/bin/env bash
# Installs what is missing, builds, and runs every test (CTest labels unit, gl, integration, hard,
# matrix).
#   scripts/test.sh              all tests
#   scripts/test.sh -L unit      only one label (any ctest arguments are passed through)
#   scripts/test.sh --sanitize   ASan+UBSan build in build-asan/, then the whole suite but the
#                                label matrix (every method against brute force on many scenes:
#                                pixels, not memory; the same code runs in the other tests);
#                                ctest arguments replace that selection
#   scripts/test.sh --tsan       TSan build in build-tsan/ of the threaded parts (transport, camera
#                                buffer, the switch node's camera thread in one cluster run and the
#                                strangers-at-the-ports test, the --serve nodes' busy door, a node
#                                killed and one restarted, also with a cluster key and in latest
#                                camera mode), then
#                                those tests (ctest arguments replace the default selection)
# The normal and the ASan+UBSan suites run as many tests at a time as the machine has CPUs, at
# most 4 (CTEST_PARALLEL_LEVEL, or a -j among the ctest arguments, sets another number); most of
# their time is waits and process start-ups, and every test is written for a loaded machine. The
# TSan suite runs one at a time (its recovery tests' timing under TSan is tight).
set -euo pipefail
source "$(dirname "$0")/lib.sh"  # --version
occ_help_first "$@"  # before anything is installed or built
cd "$(dirname "$0")/.."
scripts/setup.sh

MODE=normal
case "${1:-}" in
  --sanitize) MODE=asan; shift ;;
  --tsan) MODE=tsan; shift ;;
esac

# No llvmpipe rasteriser threads: Mesa 22.3's llvmpipe can free a fence while its rasteriser
# thread is still unlocking the fence's mutex, which corrupts the heap (rarely; more often on an
# oversubscribed machine, as under ctest -j2; docs/hard_cases.md). Rasterising on the calling thread
# cannot race. The tests check frames and sets, not speed.
export LP_NUM_THREADS=${LP_NUM_THREADS:-0}

case "$MODE" in
  asan)
    export OCC_BUILD_DIR=build-asan
    # fast_unwind_on_malloc=0 would deadlock OSMesa: keep the default fast unwinder.
    # intercept_tls_get_addr=0: the sanitizer runtime guesses glibc's dynamic-TLS header from where
    # a block lands and can guess wrong; LeakSanitizer's tracer then dies at exit ("Tracer caught
    # signal 11", https://github.com/google/sanitizers/issues/1322), here in a switch node of ClusterLod.VisiblePixel... once
    # the heap's layout moved. Static TLS and every other root are still scanned.
    export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:detect_stack_use_after_return=0:intercept_tls_get_addr=0
    export LSAN_OPTIONS=suppressions=$PWD/tests/lsan.supp:print_suppressions=0
    export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
    scripts/build.sh -DOCC_SANITIZE=ON
    [ $# -gt 0 ] || set -- -LE matrix
    ;;
  tsan)
    export OCC_BUILD_DIR=build-tsan
    export TSAN_OPTIONS="suppressions=$PWD/tests/tsan.supp:halt_on_error=1:second_deadlock_stack=1:report_signal_unsafe=0"
    if [ ! -f build-tsan/CMakeCache.txt ]; then
      cmake -S . -B build-tsan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DOCC_TSAN=ON >/dev/null
    fi
    cmake --build build-tsan -j"$(nproc)" --target core_test net_transport_test cluster_test hard_faults_test \
      recovery_test membership_test switch_node render_client frame_diff link_relay occlusion_server
    if [ $# -eq 0 ]; then
      set -- -R '^(CameraBuffer|Loopback|Handshake|Connect|Connection|Listener)\.|^Cluster\.CityWalkEqualsReference$|^HardFaults\.|^Serve\.|^Recovery\.(KilledNode1|RestartedNode0|KeyedRestartedNode|LatestCameraMode)'
    fi
    ;;
  normal)
    scripts/build.sh
    ;;
esac
if [ "$MODE" != tsan ]; then
  cpus=$(nproc)
  export CTEST_PARALLEL_LEVEL=${CTEST_PARALLEL_LEVEL:-$((cpus < 4 ? cpus : 4))}
fi
BUILD_DIR=${OCC_BUILD_DIR:-build}
# The scripts the tests run (cluster.sh, netlab.sh, ...) take the binaries of this build.
export OCC_BIN=${OCC_BIN:-$PWD/$BUILD_DIR/bin}
ctest --test-dir "$BUILD_DIR" --output-on-failure --timeout 900 "$@"
