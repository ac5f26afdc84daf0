#!/usr/bin/env bash
# Runs the occlusion-switch cluster on this machine: switch nodes 0 and 1 and the render client
# on 127.0.0.1 with ephemeral ports (port files, no fixed ports). Prints the render client's
# summary, keeps every process's log in the output folder, and exits non-zero if any process
# failed or hung (bounded waits). Ctrl-C stops all three.
#
#   scripts/cluster.sh --scene S [--path P] [--frames N] [--out DIR] [extra args]
#
# --path walk|orbit|fly (N frames from --frames, default 60), walk:N, or a CSV file.
# Extra args reach all three processes (--width W --height H --camera-mode M --full-sets --gl B
# --arity ...), except render-client-only ones (--no-images --lookahead N) and node-only ones
# (--diff-chunk B), which go where they belong. OCC_BIN overrides the binaries' folder;
# OCC_MAX_SECONDS (default 900) bounds the whole run.
set -uo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
BIN=${OCC_BIN:-$here/build/bin}
MAX_SECONDS=${OCC_MAX_SECONDS:-900}

scene="" path="walk" frames=60 out="out/cluster"
common=() rvg_only=() node_only=()
while [ $# -gt 0 ]; do
  case "$1" in
    --scene) scene=$2; shift 2 ;;
    --path) path=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --no-images) rvg_only+=("$1"); shift ;;
    --lookahead) rvg_only+=("$1" "$2"); shift 2 ;;
    --diff-chunk) node_only+=("$1" "$2"); shift 2 ;;
    --full-sets) common+=("$1"); shift ;;
    -h|--help) sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    --*) [ $# -ge 2 ] || { echo "error: $1 needs a value" >&2; exit 2; }
         common+=("$1" "$2"); shift 2 ;;
    *) echo "error: unexpected argument '$1' (see scripts/cluster.sh --help)" >&2; exit 2 ;;
  esac
done
[ -n "$scene" ] || { echo "error: --scene is required (e.g. --scene city)" >&2; exit 2; }
case "$path" in walk|orbit|fly) path="$path:$frames" ;; esac
for b in switch_node render_client; do
  [ -x "$BIN/$b" ] || { echo "error: $BIN/$b not built (run scripts/build.sh)" >&2; exit 2; }
done
mkdir -p "$out"
rm -f "$out"/node0.port "$out"/node1.port "$out"/frame_*.png
export LP_NUM_THREADS=${LP_NUM_THREADS:-1}

pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done; }
trap 'echo "cluster: interrupted, stopping all processes" >&2; cleanup; exit 130' INT TERM

wait_port() {  # file pid name
  for _ in $(seq 1 600); do
    [ -s "$1" ] && { cat "$1"; return 0; }
    kill -0 "$2" 2>/dev/null || { echo "error: $3 exited before listening (see $out/$3.log)" >&2; return 1; }
    sleep 0.1
  done
  echo "error: $3 did not write its port file within 60 s" >&2; return 1
}

"$BIN/switch_node" --id 0 --scene "$scene" --port-file "$out/node0.port" "${common[@]}" "${node_only[@]}" \
  >"$out/node0.log" 2>&1 &
pids+=($!)
p0=$(wait_port "$out/node0.port" "${pids[0]}" node0) || { cleanup; exit 1; }
"$BIN/switch_node" --id 1 --scene "$scene" --peer "127.0.0.1:$p0" --port-file "$out/node1.port" \
  "${common[@]}" "${node_only[@]}" >"$out/node1.log" 2>&1 &
pids+=($!)
p1=$(wait_port "$out/node1.port" "${pids[1]}" node1) || { cleanup; exit 1; }
"$BIN/render_client" --scene "$scene" --path "$path" --out "$out" --connect "127.0.0.1:$p0" \
  --connect "127.0.0.1:$p1" "${common[@]}" "${rvg_only[@]}" >"$out/render_client.log" 2>&1 &
pids+=($!)

# Bounded wait for all three.
status=0
deadline=$((SECONDS + MAX_SECONDS))
names=(node0 node1 render_client)
for i in 2 0 1; do
  while kill -0 "${pids[$i]}" 2>/dev/null && [ $SECONDS -lt $deadline ]; do sleep 0.2; done
  if kill -0 "${pids[$i]}" 2>/dev/null; then
    echo "error: ${names[$i]} still running after ${MAX_SECONDS} s: killed" >&2
    cleanup; status=1
  fi
  wait "${pids[$i]}"; rc=$?
  if [ $rc -ne 0 ]; then
    echo "cluster: ${names[$i]} exited with status $rc; last lines of $out/${names[$i]}.log:" >&2
    tail -n 5 "$out/${names[$i]}.log" | sed 's/^/  /' >&2
    status=1
  fi
  # Once the render client is done, give the nodes a short grace period.
  [ $i -eq 2 ] && deadline=$((SECONDS + 30))
done
grep -h "^summary:" "$out/render_client.log" || true
grep -h "HC frames" "$out/node0.log" "$out/node1.log" || true
exit $status
