#!/usr/bin/env bash
# Benchmarks every way occswitch can render the same path, one after another, on the same
# scene, path and viewport (paper section 5, Tables 1-3, Figures 3-6):
#   1 none      reference renderer, no culling: brute force (also counts the exactly visible
#               nodes with an item buffer)
#   2 frustum   hierarchical frustum culling
#   3 stop-and-wait  single process, one occlusion query at a time, waiting for each
#   4 chc       single process, coherent hierarchical culling (previous visibility, no waiting)
#   5 gigawalk  depth-readback occlusion server (software HZB) + render client: 2 processes
#   6 switch    the occlusion switch: 2 switch nodes + render client: 3 processes
#   (what incremental transmission saves: the switch run's full_set_bytes beside its bytes)
#   7 OpenSceneGraph: no culling, frustum culling, OcclusionQueryNode, when the OSG peer of
#     ../shared/peers/osg is built (OSG_PEER=/path/to/osg_peer, default /tmp/osgpeer-build/osg_peer);
#     skipped with a message otherwise. A generated scene (city, layout) reaches it as the glTF
#     file scene_export writes (the same geometry and placement).
# Every method's frames are compared with its own renderer's brute force (wrong pixels, total and
# worst frame; the two multi-process methods get a second run with images for that, so PNG writing
# never counts as frame time). Each process's CPU time per frame and stage comes from the process
# CPU clock; the report models the frame time with one machine per process from it
# (scripts/bench_report.py; --model-delay-ms: one-way link delay for the model, default 0).
# Writes OUT/bench.csv, OUT/bench.md, OUT/fps_along_path.png, OUT/nodes_sent.png and each run's
# stats.csv, logs and wrong.txt in OUT/<method>/; frames are deleted after the comparison unless
# --keep-frames. Prints figures; asserts nothing about speed.
#
#   scripts/bench.sh --scene S [--path P] [--frames N] [--width W --height H] [--out DIR]
#                    [--model-delay-ms D] [--keep-frames] [--backend cpu|queries|gpu-pyramid|cpu-pyramid]
#
# --path walk|orbit|fly gets --frames frames (default walk, 200); the viewport defaults to 512x512 as
# everywhere. --backend goes to the switch nodes (how the OR draws depth and HC tests boxes;
# switch_node --help); without it they choose by the renderer (auto).
set -euo pipefail
source "$(dirname "$0")/lib.sh"
scene="" path="walk" frames=200 width=$OCC_WIDTH height=$OCC_HEIGHT out="out/bench" model_delay_ms=0 keep_frames=0 backend=""
while [ $# -gt 0 ]; do
  case "$1" in
    --scene|--path|--frames|--width|--height|--out|--model-delay-ms|--backend) occ_set "$@"; shift 2 ;;
    --keep-frames) keep_frames=1; shift ;;
    -h|--help) occ_usage; exit 0 ;;
    *) occ_unexpected "$1" ;;
  esac
done
[ -n "$scene" ] || occ_die "--scene is required"
path=$(occ_frames_path "$path" "$frames")
occ_require_bins render_client switch_node occlusion_server frame_diff
mkdir -p "$out"
export LP_NUM_THREADS=${LP_NUM_THREADS:-1}
view=(--width "$width" --height "$height")
switch_flags=()
[ -z "$backend" ] || switch_flags=(--backend "$backend")
log() { echo "bench: $*" >&2; }
# wrong DIR BRUTE_FORCE_FRAMES [FRAMES]: frame_diff (per frame, then its summary line) into DIR/wrong.txt
wrong() { "$BIN/frame_diff" "$2" "${3:-$1}" >"$1/wrong.txt"; }
drop_frames() { [ "$keep_frames" = 1 ] || rm -f "$1"/frame_*.png; }

osg_peer=${OSG_PEER:-/tmp/osgpeer-build/osg_peer}
osg_run=$here/../shared/peers/osg/run.sh
osg_scene="" osg_skip=""
if [ ! -x "$osg_peer" ]; then
  osg_skip="no OSG peer at $osg_peer (build it as ../shared/peers/osg/README.md says, or set OSG_PEER)"
elif [ ! -x "$osg_run" ]; then
  osg_skip="$osg_run not found"
else
  osg_scene=$out/osg_scene/scene.gltf  # what scene_export writes
  case "$scene" in *.gltf|*.glb) [ -f "$scene" ] && osg_scene=$scene ;; esac
fi
rm -rf "$out"/osg_*

for cull in none frustum stop-and-wait chc; do
  log "$cull"
  extra=(); [ "$cull" = none ] && extra=(--exact)  # its OUT/path.csv: the cameras for the OSG rows
  if [ "$cull" = none ] && [ "$osg_scene" = "$out/osg_scene/scene.gltf" ]; then
    mkdir -p "$out/osg_scene"
    "$BIN/scene_export" --scene "$scene" --out "$osg_scene" >"$out/osg_scene/log.txt" 2>&1
  fi
  mkdir -p "$out/$cull"
  # render_ms and cpu_ms stop before the PNG is written: one run gives times and frames.
  "$BIN/render_client" --scene "$scene" --path "$path" "${view[@]}" --cull "$cull" \
    "${extra[@]}" --out "$out/$cull" >"$out/$cull/log.txt" 2>&1
  [ "$cull" = none ] || wrong "$out/$cull" "$out/none"
done

# gigawalk DIR [--images off]: the occlusion server and a render client with one --connect.
gigawalk() {
  local dir=$1 server
  shift
  mkdir -p "$dir"
  rm -f "$dir/server.port"
  "$BIN/occlusion_server" --scene "$scene" "${view[@]}" --port-file "$dir/server.port" >"$dir/server.log" 2>&1 &
  server=$!
  for _ in $(seq 1 600); do [ -s "$dir/server.port" ] && break; sleep 0.1; done
  "$BIN/render_client" --scene "$scene" --path "$path" "${view[@]}" "$@" --on-node-failure exit --out "$dir" \
    --connect "127.0.0.1:$(cat "$dir/server.port")" >"$dir/log.txt" 2>&1
  wait $server
}
log "gigawalk (occlusion_server + render_client)"
gigawalk "$out/gigawalk" --images off
log "gigawalk, frames for the comparison"
gigawalk "$out/gigawalk_frames"
wrong "$out/gigawalk" "$out/none" "$out/gigawalk_frames"
drop_frames "$out/gigawalk_frames"

log "switch (3 processes)"
"$here/scripts/cluster.sh" --scene "$scene" --path "$path" "${view[@]}" "${switch_flags[@]}" --on-node-failure exit --images off --out "$out/switch" >/dev/null
cp "$out/switch/render_client.log" "$out/switch/log.txt"
log "switch, frames for the comparison"
"$here/scripts/cluster.sh" --scene "$scene" --path "$path" "${view[@]}" "${switch_flags[@]}" --on-node-failure exit --out "$out/switch_frames" >/dev/null
wrong "$out/switch" "$out/none" "$out/switch_frames"
drop_frames "$out/switch_frames"

# OpenSceneGraph on the same cameras (the path as CSV) and viewport, each mode against OSG's own
# brute force (its shading differs from ours).
if [ -n "$osg_skip" ]; then
  log "OpenSceneGraph rows skipped: $osg_skip"
else
  for mode in none frustum oqn; do
    log "OpenSceneGraph $mode"
    mkdir -p "$out/osg_$mode"
    rc=0
    OSG_PEER_BIN=$osg_peer "$osg_run" "$osg_scene" "$out/none/path.csv" "$mode" "${view[@]}" --verbose \
      --out "$out/osg_$mode" >"$out/osg_$mode/log.txt" 2>&1 || rc=$?
    if [ $rc -ne 0 ]; then
      cp "$out/osg_$mode/log.txt" "$out/osg_failed.log"
      log "OpenSceneGraph $mode failed (status $rc, log in $out/osg_failed.log), its rows are left out"
      rm -rf "$out"/osg_none "$out"/osg_frustum "$out"/osg_oqn
      break
    fi
    # "frame N ms=X drawn=D" per frame (timed up to glFinish, the PNG readback is not).
    awk 'BEGIN { print "frame,render_ms,objects_drawn" }
         $1 == "frame" { sub("ms=", "", $3); sub("drawn=", "", $4); print $2 "," $3 "," $4 }' \
      "$out/osg_$mode/log.txt" >"$out/osg_$mode/stats.csv"
  done
  if [ -d "$out/osg_oqn" ]; then
    for mode in frustum oqn; do wrong "$out/osg_$mode" "$out/osg_none"; done
    for mode in none frustum oqn; do drop_frames "$out/osg_$mode"; done
  fi
  rm -rf "$out/osg_scene"
fi
for cull in frustum stop-and-wait chc none; do drop_frames "$out/$cull"; done

python3 "$here/scripts/bench_report.py" "$out" "$scene" "$path" "$width" "$height" --model-delay-ms "$model_delay_ms"
if command -v gnuplot >/dev/null; then
  gnuplot -e "out='$out'" "$here/scripts/bench_plots.gp" && log "plots: $out/fps_along_path.png $out/nodes_sent.png"
fi
cat "$out/bench.md"
