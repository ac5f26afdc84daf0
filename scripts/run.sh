#!/usr/bin/env bash
# The main job on a default scene that needs no extra files: installs what is missing, builds,
# renders a walk through a generated city and writes frames + stats to out/run/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
OUT=${OUT:-out/run}
mkdir -p "$OUT"
export LP_NUM_THREADS=${LP_NUM_THREADS:-1}
build/bin/render_client --reference --scene city --path walk:60 --width 640 --height 480 --out "$OUT" "$@"
echo "frames and stats.csv in $OUT"
