#!/usr/bin/env bash
# Configures and builds occswitch into build/ (or $OCC_BUILD_DIR). Extra args go to cmake configure.
set -euo pipefail
case "${1:-}" in  # before anything is installed or built
  -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
  --version) echo "$(basename "$0") (occswitch) $(cat "$(dirname "$0")/../VERSION")"; exit 0 ;;
esac
cd "$(dirname "$0")/.."
BUILD_DIR=${OCC_BUILD_DIR:-build}
if [ ! -f "$BUILD_DIR/CMakeCache.txt" ] || [ $# -gt 0 ]; then
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo "$@" >/dev/null
fi
cmake --build "$BUILD_DIR" -j"$(nproc)"
