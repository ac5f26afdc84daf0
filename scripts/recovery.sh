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
"$BIN/render_client" --scene "$scene" --path "$path" --out "$out" --images off --connect "127.0.0.1:$p0" \
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
# Per mode: frames, median and mean frame interval, mean render time (rvg_ms), mean triangles;
# then the frames from the kill to the resync and to the switch's return.
python3 - "$out/stats.csv" <<'PY'
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
print(f"{'mode':8} {'frames':>6} {'median_ms':>10} {'mean_ms':>9} {'rvg_ms':>7} {'triangles':>10} {'visible':>8}")
for m in ("switch", "resync", "single", "frustum"):
    r = [x for x in rows if x["mode"] == m]
    if not r:
        continue
    iv = [float(x["frame_interval_ms"]) for x in r]
    mean = lambda k: statistics.mean(float(x[k]) for x in r)
    print(f"{m:8} {len(r):6d} {statistics.median(iv):10.2f} {statistics.mean(iv):9.2f} {mean('rvg_ms'):7.2f} "
          f"{mean('triangles'):10.0f} {mean('visible'):8.1f}")
modes = [x["mode"] for x in rows]
first = next((i for i, m in enumerate(modes) if m != "switch"), None)
if first is not None:
    resync = next((i for i in range(first, len(modes)) if modes[i] == "resync"), None)
    back = next((i for i in range(first, len(modes)) if modes[i] == "switch"), None)
    print(f"first degraded frame {first}: its interval {float(rows[first]['frame_interval_ms']):.1f} ms; "
          f"resync at {resync}; switch again at {back}")
PY
exit $status
