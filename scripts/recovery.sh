#!/usr/bin/env bash
# What degraded mode costs (docs/recovery.md): runs the cluster on 127.0.0.1, kills switch node
# KILL_NODE once the render client has shown --kill-at frames, restarts it on its port once it has
# shown --restart-at frames (0: never; --kill-both: kill both nodes, the client frustum-culls), and
# prints per frame mode (stats.csv column `mode`) the frames and the median / mean frame interval
# and render time, plus the frames from the kill to the first frame served again.
#
#   scripts/recovery.sh --scene S [--path P] [--kill-at N] [--restart-at M] [--kill-node K]
#                       [--kill-both] [--out DIR] [extra args for all three, e.g. --width 512 --height 512]
set -uo pipefail
source "$(dirname "$0")/lib.sh"
scene="" path="walk:300" kill_at=100 restart_at=0 kill_node=1 kill_both=0 out="out/recovery"
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    --scene|--path|--out) occ_set "$@"; shift 2 ;;
    --kill-at) occ_need_value "$@"; kill_at=$2; shift 2 ;;
    --restart-at) occ_need_value "$@"; restart_at=$2; shift 2 ;;
    --kill-node) occ_need_value "$@"; kill_node=$2; shift 2 ;;
    --kill-both) kill_both=1; shift ;;
    -h|--help) occ_usage; exit 0 ;;
    --*) occ_need_value "$@"; extra+=("$1" "$2"); shift 2 ;;
    *) occ_unexpected "$1" ;;
  esac
done
[ -n "$scene" ] || occ_die "--scene is required"
[[ "$kill_node" =~ ^[01]$ ]] || occ_die "--kill-node must be 0 or 1"
occ_require_bins switch_node render_client
export LP_NUM_THREADS=${LP_NUM_THREADS:-1}
rm -rf "$out" && mkdir -p "$out"
pids=()
trap 'for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done' EXIT
port() { for _ in $(seq 1 600); do [ -s "$1" ] && { cat "$1"; return; }; sleep 0.1; done; occ_die "no port file $1"; }
rows() { [ -f "$out/stats.csv" ] && echo $(($(wc -l <"$out/stats.csv") - 1)) || echo 0; }
node() {  # id port-args log
  local id=$1 log=$3
  local peer=()
  [ "$id" = 1 ] && peer=(--peer "127.0.0.1:$p0")
  "$BIN/switch_node" --id "$id" --scene "$scene" "${peer[@]}" $2 "${extra[@]}" >"$out/$log" 2>&1 &
  pids+=($!)
}
node 0 "--port 0 --port-file $out/n0.port" node0.log; n0=${pids[-1]}; p0=$(port "$out/n0.port")
node 1 "--port 0 --port-file $out/n1.port" node1.log; n1=${pids[-1]}; p1=$(port "$out/n1.port")
"$BIN/render_client" --scene "$scene" --path "$path" --out "$out" --no-images --connect "127.0.0.1:$p0" \
  --connect "127.0.0.1:$p1" "${extra[@]}" >"$out/render_client.log" 2>&1 &
rvg=$!
while kill -0 $rvg 2>/dev/null && [ "$(rows)" -lt "$kill_at" ]; do sleep 0.02; done
if [ $kill_both = 1 ]; then kill -9 $n0 $n1; else kill -9 $([ "$kill_node" = 0 ] && echo $n0 || echo $n1); fi
echo "recovery: killed at frame $(rows)" >&2
if [ "$restart_at" -gt 0 ] && [ $kill_both = 0 ]; then
  while kill -0 $rvg 2>/dev/null && [ "$(rows)" -lt "$restart_at" ]; do sleep 0.02; done
  p=$([ "$kill_node" = 0 ] && echo "$p0" || echo "$p1")
  node "$kill_node" "--port $p --port-file $out/again.port" "node${kill_node}_again.log"
  echo "recovery: restarted node $kill_node at frame $(rows)" >&2
fi
wait $rvg; status=$?
grep -E "^(summary|modes):|degraded|resync|is back" "$out/render_client.log"
# Per mode: frames, median and mean frame interval, mean render time (rvg_ms), mean triangles.
awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
  { m = $c["mode"]; n[m]++; iv[m, n[m]] = $c["frame_interval_ms"]; s[m] += $c["frame_interval_ms"];
    r[m] += $c["rvg_ms"]; t[m] += $c["triangles"] }
  END { printf "%-8s %6s %10s %10s %10s %12s\n", "mode", "frames", "median_ms", "mean_ms", "rvg_ms", "triangles";
    for (m in n) { k = n[m]; for (i = 1; i <= k; i++) v[i] = iv[m, i]; asort(v);
      printf "%-8s %6d %10.2f %10.2f %10.2f %12.0f\n", m, k, v[int((k + 1) / 2)], s[m] / k, r[m] / k, t[m] / k; delete v } }' \
  "$out/stats.csv"
exit $status
