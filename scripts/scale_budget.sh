#!/usr/bin/env bash
# Memory and frame rate against scene size with the geometry resident within a budget and with
# all of it resident (docs/scale.md): the switch (three processes) on the generated plant
# at several sizes, one run per size and mode, on one path. Per run: mean fps, the median and p99
# frame interval, the peak resident memory of the three processes together, the time from the
# start of the cluster to its first frame, and the render client's waits for geometry. Writes
# OUT/budget.csv and, with gnuplot, OUT/budget.png.
#
# usage: scripts/scale_budget.sh --out DIR [--sizes "0.5 4 13 80 200"] [--modes "auto all"]
#                                [--path walk:300] [--width W] [--height H] [--pixel-error TAU]
#   --out DIR          where the runs, budget.csv and budget.png go (required)
#   --sizes "M ..."    plant sizes in millions of triangles (default "0.5 4 13 80")
#   --modes "B ..."    --geometry-budget values (default "auto all": the default budget, everything
#                      resident); a mode whose three processes would not fit is skipped by
#                      --max-resident-m
#   --max-resident-m M the largest size run with --geometry-budget all (default 80: 15 GB there)
#   --path P           camera path (default walk:300)
#   --width, --height  viewport (default 1024 x 1024)
#   --pixel-error TAU  tau (default 1)
# The first run of a size builds its scene and LOD caches (minutes at 80 and 200; docs/scale.md),
# before its timed run: that build is a run of its own (node 0 alone, then stopped).
set -uo pipefail
source "$(dirname "$0")/lib.sh"
cd "$here"
out="" sizes="0.5 4 13 80" modes="auto all" max_resident_m=80 path=walk:300 width=1024 height=1024 pixel_error=1
while [ $# -gt 0 ]; do
  case $1 in
    --out|--sizes|--modes|--max-resident-m|--path|--width|--height|--pixel-error) occ_set "$@"; shift 2 ;;
    -h|--help) occ_usage; exit 0 ;;
    *) occ_unexpected "$1" ;;
  esac
done
[ -n "$out" ] || occ_die "--out DIR is required (see $OCC_SCRIPT --help)"
occ_require_bins render_client switch_node
export LP_NUM_THREADS=${LP_NUM_THREADS:-1}
mkdir -p "$out"
csv=$out/budget.csv
echo "size_m,mode,mean_fps,median_interval_ms,p99_interval_ms,peak_rss_sum_mb,first_frame_s,geometry_waits,geometry_wait_ms" >"$csv"
for m in $sizes; do
  # The caches first (not timed): node 0 alone builds them, then waits in vain for its peers.
  "$BIN"/switch_node --id 0 --scene plant:$m --pixel-error "$pixel_error" --width "$width" --height "$height" \
    --timeout-ms 1000 >"$out/plant_${m}_caches.log" 2>&1
  for mode in $modes; do
    if [ "$mode" = all ] && python3 -c "import sys; sys.exit(0 if float('$m') > float('$max_resident_m') else 1)"; then
      echo "scale_budget: plant:$m --geometry-budget all skipped (above --max-resident-m $max_resident_m)" >&2
      continue
    fi
    d=$out/plant_${m}_$mode
    echo "scale_budget: plant:$m --geometry-budget $mode ..." >&2
    t0=$(date +%s.%N)
    if ! OCC_START_AT_ONCE=1 OCC_PORT_WAIT_S=${OCC_PORT_WAIT_S:-2400} OCC_MAX_SECONDS=${OCC_MAX_SECONDS:-3000} scripts/cluster.sh \
      --scene plant:$m --path "$path" --width "$width" --height "$height" --pixel-error "$pixel_error" --images off \
      --timeout-ms 900000 --geometry-budget "$mode" --out "$d" >"$d.log" 2>&1; then
      echo "error: scale_budget.sh: plant:$m --geometry-budget $mode failed: $(tail -1 "$d.log")" >&2
      continue
    fi
    rss=$(grep -ho 'peak_rss_mb=[0-9]*' "$d"/*.log | awk -F= '{s += $2} END {print s}')
    first=$(sed -nE 's/.*first frame shown .* \(wall clock ([0-9.]+)\).*/\1/p' "$d/render_client.log" | head -1)
    python3 - "$d/stats.csv" "$m" "$mode" "$rss" "$t0" "${first:-0}" >>"$csv" <<'PY'
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
iv = sorted(float(r["frame_interval_ms"]) for r in rows[1:])  # frame 0's interval is the start
fps = 1000.0 * len(iv) / sum(iv)
p99 = iv[min(len(iv) - 1, int(round(0.99 * (len(iv) - 1))))]
waits = sum(float(r["geometry_waits"]) for r in rows)
wait_ms = sum(float(r["geometry_wait_ms"]) for r in rows)
first = float(sys.argv[6]) - float(sys.argv[5]) if float(sys.argv[6]) > 0 else -1
print(f"{sys.argv[2]},{sys.argv[3]},{fps:.2f},{statistics.median(iv):.1f},{p99:.1f},{sys.argv[4]},{first:.1f},"
      f"{waits:.0f},{wait_ms:.0f}")
PY
    tail -1 "$csv" >&2
  done
done
column -s, -t "$csv" >&2
if command -v gnuplot >/dev/null; then
  for mode in $modes; do awk -F, -v m="$mode" '$2 == m' "$csv" >"$out/budget_$mode.csv"; done
  gnuplot -e "dir='$out'" scripts/scale_budget_plot.gp && echo "scale_budget: wrote $out/budget.png" >&2
else
  echo "scale_budget: gnuplot not found: no plot (budget.csv has the figures)" >&2
fi
