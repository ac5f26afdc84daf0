#!/usr/bin/env bash
# Network experiments: what latency and bandwidth do to the occlusion switch. Runs the cluster
# (scripts/cluster.sh) with every link routed through link_relay, for each delay x rate (diff chunks
# of the paper's b = 100 ids: b from 10 to 1000 measured alike, docs/latency.md). All traffic
# stays on 127.0.0.1.
#
#   scripts/netlab.sh --scene S [--path P] [--frames N] [--delays "0 1 5 20"] [--rates "10 100 1000"]
#                     [--camera-mode latest|lockstep]
#                     [--repeats N] [--width W --height H] [--out DIR] [--netns]
#
# --repeats N (default 3) runs every point N times, interleaved (all points once, then all again),
# so that a slow minute of the machine spreads over the points instead of landing on one; the
# figures are the median over the runs, with their min and max.
#
# --path walk|orbit|fly gets --frames frames (default walk, 150); the viewport defaults to 512x512 as
# everywhere; --camera-mode as in scripts/cluster.sh (default latest here).
#
# Writes OUT/net_runs.csv (one row per run: repeat, delay_ms, rate_mbit, chunk_ids, fps, latency
# mean/p95, bytes/frame, frames completed), OUT/net.csv (per point: runs, failed runs, the frames
# the figures rest on (all runs, shortest run), and median,min,max of each figure:
# scripts/netlab_aggregate.py), OUT/net_fps.png, OUT/net_latency.png (medians
# with min-max bars). Rates are Mbit/s per direction; delays are one-way, per link. --netns
# (root): the three processes run in three network namespaces joined by veth pairs, rates as tc
# tbf qdiscs (see scripts/cluster.sh).
set -euo pipefail
source "$(dirname "$0")/lib.sh"
scene="" path="walk" frames=150 delays="0 1 5 20" rates="10 100 1000"
camera_mode=latest width=$OCC_WIDTH height=$OCC_HEIGHT out="out/netlab" netns=() repeats=3
while [ $# -gt 0 ]; do
  case "$1" in
    --scene|--path|--frames|--delays|--rates|--camera-mode|--width|--height|--out|--repeats) occ_set "$@"; shift 2 ;;
    --mode) occ_die "--mode is now --camera-mode (as in cluster.sh and the binaries)" ;;
    --netns) netns=(--netns); shift ;;
    -h|--help) occ_usage; exit 0 ;;
    *) occ_unexpected "$1" ;;
  esac
done
[ -n "$scene" ] || occ_die "--scene is required"
case "$camera_mode" in latest|lockstep) ;; *) occ_die "--camera-mode '$camera_mode': expected latest or lockstep" ;; esac
[[ "$repeats" =~ ^[1-9][0-9]*$ ]] || occ_die "--repeats '$repeats': expected a whole number >= 1"
path=$(occ_frames_path "$path" "$frames")
mkdir -p "$out"
runs_csv="$out/net_runs.csv" csv="$out/net.csv"
echo "repeat,delay_ms,rate_mbit,chunk_ids,fps,latency_ms_mean,latency_ms_p95,bytes_per_frame,frames" >"$runs_csv"

run() {  # repeat delay rate chunk (always 100 ids: the nodes' fixed b)
  local dir="$out/d$2_r$3_b$4_k$1"
  echo "netlab: repeat $1/$repeats: delay $2 ms, rate $3 Mbit/s" >&2
  if ! "$here/scripts/cluster.sh" --scene "$scene" --path "$path" --width "$width" --height "$height" \
      --camera-mode "$camera_mode" --images off --on-node-failure exit --link "$2:$3" "${netns[@]}" --out "$dir" >/dev/null; then
    echo "netlab: run failed (see $dir)" >&2
    echo "$1,$2,$3,$4,,,,,0" >>"$runs_csv"
    return
  fi
  local s
  s=$(grep -h "^summary:" "$dir/render_client.log")
  get() { sed -n "s/.* $1=\([^ ]*\).*/\1/p" <<<"$s"; }
  echo "$1,$2,$3,$4,$(get mean_fps),$(get latency_ms_mean),$(get latency_ms_p95),$(get mean_bytes_per_frame),$(get frames)" >>"$runs_csv"
}

# The points (delay rate chunk), each once.
points=()
for d in $delays; do for r in $rates; do points+=("$d $r 100"); done; done
mapfile -t points < <(printf '%s\n' "${points[@]}" | awk '!seen[$0]++')
for ((k = 1; k <= repeats; k++)); do
  for p in "${points[@]}"; do run "$k" $p; done
done
python3 "$here/scripts/netlab_aggregate.py" "$runs_csv" "$csv"
column -s, -t "$csv"

if command -v gnuplot >/dev/null; then
  gnuplot -e "csv='$csv'; out='$out'; rates='$rates'" "$here/scripts/netlab_plots.gp"
  echo "netlab: plots in $out/net_fps.png, $out/net_latency.png" >&2
fi
