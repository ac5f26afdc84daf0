#!/usr/bin/env bash
# The spikes measurement matrix (docs/spikes.md): every path at 512² and 1024², tau 0 and 1
# (each run's stats.csv says what the whole sets would have taken), and an item-buffer run (every camera) for PVS/exact and the exact
# set's own ids saved (what an incremental set could save at best on the path).
#   scripts/spikes_matrix.sh OUT [extra cluster args...]      e.g. OUT=out/sp/base
# Paths: the generated city walks (45x45 passes through buildings, 20x20 follows a street), street
# walks with 90° turns (scripts/street_walk.py) and the duplex layout walk. SKIP_EXACT=1 skips the
# item-buffer runs (they do not depend on the cluster's flags). ONLY=label limits to one path.
set -uo pipefail
source "$(dirname "$0")/lib.sh"
cd "$here"
case "${1:-}" in
  -h|--help) occ_usage; exit 0 ;;
  ""|-*) occ_die "give the output folder first (see $OCC_SCRIPT --help)" ;;
esac
out=$1; shift
export LP_NUM_THREADS=1
BIN=${OCC_BIN:-build/bin}
mkdir -p "$out" out/sp
python3 scripts/street_walk.py --city 45x45:4 --frames 300 --out out/sp/street45.csv
python3 scripts/street_walk.py --city 20x20:4 --frames 300 --out out/sp/street20.csv
duplex=layout:4x4:../shared/scenes/duplex/Duplex_A_20110505.gltf
paths=("c45walk city:45x45:4:16:2 walk:300" "c45street city:45x45:4:16:2 out/sp/street45.csv"
       "c20walk city:20x20:4:16:2 walk:300" "c20street city:20x20:4:16:2 out/sp/street20.csv"
       "duplex $duplex walk:300")
for p in "${paths[@]}"; do
  read -r label scene path <<<"$p"
  [ -n "${ONLY:-}" ] && [ "$ONLY" != "$label" ] && continue
  for size in 512 1024; do
    ex=out/sp/exact1/${label}_$size
    if [ -z "${SKIP_EXACT:-}" ] && [ ! -s "$ex/stats.csv" ]; then
      mkdir -p "$ex"
      "$BIN"/render_client --scene "$scene" --path "$path" --width $size --height $size \
        --images off --exact --cull frustum --out "$ex" >"$ex/log" 2>&1 || echo "exact $label $size failed" >&2
    fi
    for tau in 0 1; do
      d=$out/${label}_${size}_t$tau
      scripts/cluster.sh --scene "$scene" --path "$path" --width $size --height $size --pixel-error $tau \
        --images off --out "$d" "$@" >"$d.log" 2>&1 || { echo "run $d failed" >&2; continue; }
      args=()
      [ -s "$ex/stats.csv" ] && args+=(--exact "$ex" --exact-every 1)
      python3 scripts/spikes_report.py "$d" "${args[@]}" --label "${label} ${size}² tau $tau" | tee -a "$out/report.txt"
    done
  done
done
