#!/usr/bin/env bash
# Frame time and memory against scene size (docs/scale.md): the generated plant at
# several sizes, rendered by frustum culling and CHC (one process each) and by the switch (three
# processes), --images off, on one path. Per size and method: mean and median frame time, mean
# nodes drawn (visible set for the switch), triangles per frame, peak resident memory (the sum
# of the three processes for the switch). Writes OUT/scale.csv and, with gnuplot, OUT/scale.png.
#
# usage: scripts/scale_matrix.sh --out DIR [--sizes "0.5 2.6 13 80"] [--path walk:30]
#                                [--width W] [--height H] [--pixel-error TAU]
#   --out DIR          where the runs, scale.csv and scale.png go (required)
#   --sizes "M ..."    plant sizes in millions of triangles (default "0.5 2.6 13 80")
#   --path P           camera path (default walk:30)
#   --width, --height  viewport (default 512 x 512)
#   --pixel-error TAU  tau for the switch (default 0; frustum and CHC draw full detail)
# The first run of a size builds its scene and LOD caches (minutes at 80, see docs/scale.md);
# plant:80 takes about 6 GB per process. OCC_BIN overrides the binaries' folder.
set -uo pipefail
source "$(dirname "$0")/lib.sh"
cd "$here"
out="" sizes="0.5 2.6 13 80" path=walk:30 width=$OCC_WIDTH height=$OCC_HEIGHT pixel_error=0
while [ $# -gt 0 ]; do
  case $1 in
    --out|--sizes|--path|--width|--height|--pixel-error) occ_set "$@"; shift 2 ;;
    -h|--help) occ_usage; exit 0 ;;
    *) occ_unexpected "$1" ;;
  esac
done
[ -n "$out" ] || occ_die "--out DIR is required (see $OCC_SCRIPT --help)"
occ_require_bins render_client switch_node
W=$width H=$height tau=$pixel_error
export LP_NUM_THREADS=${LP_NUM_THREADS:-1}
mkdir -p "$out"
csv=$out/scale.csv
echo "size_m,method,mean_ms,median_ms,drawn_mean,triangles_mean,peak_rss_mb" >"$csv"
field() { sed -nE "s/.*[ ]$1=([0-9.]+).*/\1/p" <<<"$2" | tail -1; }
# stats CSV TIME DRAWN TRIANGLES: mean and median of TIME, means of DRAWN and TRIANGLES, over the
# frames after the first three (shader compilation and first uploads are not the scene's cost).
stats() {
  python3 - "$@" <<'PY'
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
rows = rows[3:] if len(rows) > 3 else rows
col = lambda k: [float(r[k]) for r in rows]
t = col(sys.argv[2])
print(f"{statistics.mean(t):.2f},{statistics.median(t):.2f},{statistics.mean(col(sys.argv[3])):.1f},"
      f"{statistics.mean(col(sys.argv[4])):.0f}")
PY
}
for m in $sizes; do
  for cull in frustum chc; do
    d=$out/plant_${m}_$cull
    echo "scale_matrix: plant:$m $cull ..." >&2
    if ! "$BIN"/render_client --cull $cull --scene plant:$m --path "$path" --width "$W" --height "$H" \
      --images off --out "$d" >"$d.log" 2>&1; then
      echo "error: scale_matrix.sh: plant:$m --cull $cull failed: $(tail -1 "$d.log")" >&2
      continue
    fi
    s=$(grep '^reference (' "$d.log" | tail -1)
    echo "$m,$cull,$(stats "$d/stats.csv" render_ms nodes_drawn triangles_drawn),$(field peak_rss_mb "$s")" >>"$csv"
  done
  d=$out/plant_${m}_switch
  echo "scale_matrix: plant:$m switch ..." >&2
  if ! OCC_PORT_WAIT_S=${OCC_PORT_WAIT_S:-2400} scripts/cluster.sh --scene plant:$m --path "$path" --width "$W" \
    --height "$H" --pixel-error "$tau" --images off --timeout-ms 900000 --out "$d" >"$d.log" 2>&1; then
    echo "error: scale_matrix.sh: plant:$m switch failed: $(tail -1 "$d.log")" >&2
    continue
  fi
  rss=$(grep -ho 'peak_rss_mb=[0-9]*' "$d"/*.log 2>/dev/null | awk -F= '{s += $2} END {print s}')
  echo "$m,switch,$(stats "$d/stats.csv" frame_interval_ms visible triangles),$rss" >>"$csv"
done
column -s, -t "$csv" >&2
if command -v gnuplot >/dev/null; then
  for m in frustum chc switch; do awk -F, -v m=$m '$2 == m' "$csv" >"$out/scale_$m.csv"; done
  gnuplot -e "dir='$out'" scripts/scale_plot.gp && echo "scale_matrix: wrote $out/scale.png" >&2
else
  echo "scale_matrix: gnuplot not found: no plot (scale.csv has the figures)" >&2
fi
