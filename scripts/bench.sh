#!/usr/bin/env bash
# Benchmarks every way occswitch can render the same path, one after another, on the same
# scene, path and viewport (paper section 5, Tables 1-3, Figures 3-6):
#   1 none      reference renderer, no culling (also counts the exactly visible nodes: item buffer)
#   2 frustum   hierarchical frustum culling
#   3 stop-and-wait  single process, one occlusion query at a time, waiting for each
#   4 chc       single process, coherent hierarchical culling (previous visibility, no waiting)
#   5 gigawalk  depth-readback occlusion server (software HZB) + render client: 2 processes
#   6 switch    the occlusion switch: 2 switch nodes + render client: 3 processes
#   (+ switch with --full-sets, for what incremental transmission saves)
# Writes OUT/bench.csv, OUT/bench.md, OUT/fps_along_path.png, OUT/nodes_sent.png and each run's
# stats.csv and logs in OUT/<method>/. Prints figures; asserts nothing about speed.
#
#   scripts/bench.sh --scene S [--path P] [--width W --height H] [--out DIR]
set -euo pipefail
[ "${1:-}" = --version ] && { echo "$(basename "$0") (occswitch) $(cat "$(dirname "$0")/../VERSION")"; exit 0; }
here=$(cd "$(dirname "$0")/.." && pwd)
BIN=${OCC_BIN:-$here/build/bin}
scene="" path="walk:200" width=640 height=480 out="out/bench"
while [ $# -gt 0 ]; do
  case "$1" in
    --scene) scene=$2; shift 2 ;;
    --path) path=$2; shift 2 ;;
    --width) width=$2; shift 2 ;;
    --height) height=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    -h|--help) sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "error: unexpected argument '$1' (see scripts/bench.sh --help)" >&2; exit 2 ;;
  esac
done
[ -n "$scene" ] || { echo "error: --scene is required" >&2; exit 2; }
for b in render_client switch_node occlusion_server; do
  [ -x "$BIN/$b" ] || { echo "error: $BIN/$b not built (run scripts/build.sh)" >&2; exit 2; }
done
mkdir -p "$out"
export LP_NUM_THREADS=${LP_NUM_THREADS:-1}
view=(--width "$width" --height "$height")
log() { echo "bench: $*" >&2; }

for cull in none frustum stop-and-wait chc; do
  log "$cull"
  extra=(); [ "$cull" = none ] && extra=(--exact)
  mkdir -p "$out/$cull"
  "$BIN/render_client" --reference --scene "$scene" --path "$path" "${view[@]}" --cull "$cull" --no-images \
    "${extra[@]}" --out "$out/$cull" >"$out/$cull/log.txt" 2>&1
done

log "gigawalk (occlusion_server + render_client)"
mkdir -p "$out/gigawalk"
rm -f "$out/gigawalk/server.port"
"$BIN/occlusion_server" --scene "$scene" "${view[@]}" --port-file "$out/gigawalk/server.port" \
  >"$out/gigawalk/server.log" 2>&1 &
server=$!
for _ in $(seq 1 600); do [ -s "$out/gigawalk/server.port" ] && break; sleep 0.1; done
"$BIN/render_client" --scene "$scene" --path "$path" "${view[@]}" --no-images --out "$out/gigawalk" \
  --connect "127.0.0.1:$(cat "$out/gigawalk/server.port")" >"$out/gigawalk/log.txt" 2>&1
wait $server

log "switch (3 processes)"
"$here/scripts/cluster.sh" --scene "$scene" --path "$path" "${view[@]}" --no-images --out "$out/switch" >/dev/null
cp "$out/switch/render_client.log" "$out/switch/log.txt"
log "switch --full-sets"
"$here/scripts/cluster.sh" --scene "$scene" --path "$path" "${view[@]}" --no-images --full-sets \
  --out "$out/switch_full" >/dev/null

python3 "$here/scripts/bench_report.py" "$out" "$scene" "$path" "$width" "$height"
if command -v gnuplot >/dev/null; then
  gnuplot -e "out='$out'" "$here/scripts/bench_plots.gp" && log "plots: $out/fps_along_path.png $out/nodes_sent.png"
fi
cat "$out/bench.md"
