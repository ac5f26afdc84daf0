#!/usr/bin/env bash
# Network experiments: what latency and bandwidth do to the occlusion switch. Runs the cluster
# (scripts/cluster.sh) with every link routed through link_relay, for each delay x rate, then for
# each diff chunk size b at one fixed delay (the paper's buffering trade-off, section 3.5). All
# traffic stays on 127.0.0.1.
#
#   scripts/netlab.sh --scene S [--path P] [--frames N] [--delays "0 1 5 20"] [--rates "10 100 1000"]
#                     [--chunks "1 10 100 1000"] [--chunk-delay-ms 5] [--camera-mode latest|lockstep]
#                     [--width W --height H] [--out DIR] [--netns]
#
# --path walk|orbit|fly gets --frames frames (default walk, 150); the viewport defaults to 512x512 as
# everywhere; --camera-mode as in scripts/cluster.sh (default latest here).
#
# Writes OUT/net.csv (delay_ms, rate_mbit, chunk_ids, fps, latency mean/p95, bytes/frame, frames
# completed), OUT/net_fps.png, OUT/net_latency.png, OUT/net_chunks.png. Rates are Mbit/s per
# direction; delays are one-way, per link. --netns (root): the three processes run in three
# network namespaces joined by veth pairs, rates as tc tbf qdiscs (see scripts/cluster.sh).
set -euo pipefail
source "$(dirname "$0")/lib.sh"
scene="" path="walk" frames=150 delays="0 1 5 20" rates="10 100 1000" chunks="1 10 100 1000" chunk_delay_ms=5
camera_mode=latest width=$OCC_WIDTH height=$OCC_HEIGHT out="out/netlab" netns=()
while [ $# -gt 0 ]; do
  case "$1" in
    --scene|--path|--frames|--delays|--rates|--chunks|--chunk-delay-ms|--camera-mode|--width|--height|--out) occ_set "$@"; shift 2 ;;
    --mode) occ_die "--mode is now --camera-mode (as in cluster.sh and the binaries)" ;;
    --netns) netns=(--netns); shift ;;
    -h|--help) occ_usage; exit 0 ;;
    *) occ_unexpected "$1" ;;
  esac
done
[ -n "$scene" ] || occ_die "--scene is required"
case "$camera_mode" in latest|lockstep) ;; *) occ_die "--camera-mode '$camera_mode': expected latest or lockstep" ;; esac
path=$(occ_frames_path "$path" "$frames")
mkdir -p "$out"
csv="$out/net.csv"
echo "delay_ms,rate_mbit,chunk_ids,fps,latency_ms_mean,latency_ms_p95,bytes_per_frame,frames" >"$csv"

run() {  # delay rate chunk
  local dir="$out/d$1_r$2_b$3"
  echo "netlab: delay $1 ms, rate $2 Mbit/s, chunk $3 ids" >&2
  if ! "$here/scripts/cluster.sh" --scene "$scene" --path "$path" --width "$width" --height "$height" \
      --camera-mode "$camera_mode" --no-images --on-node-failure exit --diff-chunk "$3" --link "$1:$2" "${netns[@]}" --out "$dir" >/dev/null; then
    echo "netlab: run failed (see $dir)" >&2
    echo "$1,$2,$3,,,,,0" >>"$csv"
    return
  fi
  local s
  s=$(grep -h "^summary:" "$dir/render_client.log")
  get() { sed -n "s/.* $1=\([^ ]*\).*/\1/p" <<<"$s"; }
  echo "$1,$2,$3,$(get mean_fps),$(get latency_ms_mean),$(get latency_ms_p95),$(get mean_bytes_per_frame),$(get frames)" >>"$csv"
}

for d in $delays; do for r in $rates; do run "$d" "$r" 100; done; done
for b in $chunks; do run "$chunk_delay_ms" 1000 "$b"; done
column -s, -t "$csv"

if command -v gnuplot >/dev/null; then
  gnuplot -e "csv='$csv'; out='$out'; chunk_delay=$chunk_delay_ms; rates='$rates'" "$here/scripts/netlab_plots.gp"
  echo "netlab: plots in $out/net_fps.png, $out/net_latency.png, $out/net_chunks.png" >&2
fi
