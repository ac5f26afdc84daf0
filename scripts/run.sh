#!/usr/bin/env bash
# The main job on a default scene that needs no extra files: installs what is missing, builds,
# and runs the occlusion-switch cluster (two switch nodes + render client, three processes on
# 127.0.0.1) along a walk through a generated city. Frames, stats.csv, logs and the summary go
# to out/run/ (or $OUT). Extra arguments go to scripts/cluster.sh (e.g. --scene, --frames,
# --width/--height, --camera-mode latest).
set -euo pipefail
source "$(dirname "$0")/lib.sh"  # --version
occ_help_first "$@"  # before anything is installed or built
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
OUT=${OUT:-out/run}
scripts/cluster.sh --scene city --path walk --frames 120 --out "$OUT" "$@"
echo "run: frames, stats.csv and logs in $OUT"
