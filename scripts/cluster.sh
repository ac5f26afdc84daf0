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
# --link DELAY_MS:RATE_MBIT[:JITTER_MS] routes every link (render client <-> each node, node 1 ->
# node 0) through a link_relay that adds that one-way delay, jitter and bandwidth cap per
# direction (user-space: the kernel here has no netem). Relay logs go to the output folder.
set -uo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
BIN=${OCC_BIN:-$here/build/bin}
MAX_SECONDS=${OCC_MAX_SECONDS:-900}

scene="" path="walk" frames=60 out="out/cluster" link=""
common=() rvg_only=() node_only=()
while [ $# -gt 0 ]; do
  case "$1" in
    --scene) scene=$2; shift 2 ;;
    --path) path=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --link) link=$2; shift 2 ;;
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
relay_args=()
if [ -n "$link" ]; then
  IFS=: read -r l_delay l_rate l_jitter <<<"$link"
  [[ "$l_delay" =~ ^[0-9.]+$ && "$l_rate" =~ ^[0-9.]+$ && "${l_jitter:-0}" =~ ^[0-9.]+$ ]] ||
    { echo "error: --link '$link': expected DELAY_MS:RATE_MBIT[:JITTER_MS] (numbers)" >&2; exit 2; }
  relay_args=(--delay-ms "$l_delay" --rate-mbit "$l_rate" --jitter-ms "${l_jitter:-0}")
fi
for b in switch_node render_client $([ -n "$link" ] && echo link_relay); do
  [ -x "$BIN/$b" ] || { echo "error: $BIN/$b not built (run scripts/build.sh)" >&2; exit 2; }
done
mkdir -p "$out"
rm -f "$out"/*.port "$out"/frame_*.png
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

# start_relay NAME TARGET_PORT: a link_relay in front of 127.0.0.1:TARGET_PORT (port in NAME.port).
start_relay() {
  "$BIN/link_relay" --target "127.0.0.1:$2" --port-file "$out/$1.port" "${relay_args[@]}" >"$out/$1.log" 2>&1 &
  pids+=($!)
}

"$BIN/switch_node" --id 0 --scene "$scene" --port-file "$out/node0.port" "${common[@]}" "${node_only[@]}" \
  >"$out/node0.log" 2>&1 &
node0_pid=$!
pids+=($node0_pid)
p0=$(wait_port "$out/node0.port" $node0_pid node0) || { cleanup; exit 1; }
peer0=$p0
if [ -n "$link" ]; then
  start_relay relay_peer "$p0"
  peer0=$(wait_port "$out/relay_peer.port" "${pids[-1]}" relay_peer) || { cleanup; exit 1; }
fi
"$BIN/switch_node" --id 1 --scene "$scene" --peer "127.0.0.1:$peer0" --port-file "$out/node1.port" \
  "${common[@]}" "${node_only[@]}" >"$out/node1.log" 2>&1 &
node1_pid=$!
pids+=($node1_pid)
p1=$(wait_port "$out/node1.port" $node1_pid node1) || { cleanup; exit 1; }
c0=$p0 c1=$p1
if [ -n "$link" ]; then
  start_relay relay_rvg0 "$p0"
  c0=$(wait_port "$out/relay_rvg0.port" "${pids[-1]}" relay_rvg0) || { cleanup; exit 1; }
  start_relay relay_rvg1 "$p1"
  c1=$(wait_port "$out/relay_rvg1.port" "${pids[-1]}" relay_rvg1) || { cleanup; exit 1; }
fi
"$BIN/render_client" --scene "$scene" --path "$path" --out "$out" --connect "127.0.0.1:$c0" \
  --connect "127.0.0.1:$c1" "${common[@]}" "${rvg_only[@]}" >"$out/render_client.log" 2>&1 &
rvg_pid=$!
pids+=($rvg_pid)

# Bounded wait for all three (the relays are stopped afterwards).
status=0
deadline=$((SECONDS + MAX_SECONDS))
for entry in "render_client:$rvg_pid" "node0:$node0_pid" "node1:$node1_pid"; do
  name=${entry%%:*} pid=${entry##*:}
  while kill -0 "$pid" 2>/dev/null && [ $SECONDS -lt $deadline ]; do sleep 0.2; done
  if kill -0 "$pid" 2>/dev/null; then
    echo "error: $name still running after its deadline: killed" >&2
    cleanup; status=1
  fi
  wait "$pid"; rc=$?
  if [ $rc -ne 0 ]; then
    echo "cluster: $name exited with status $rc; last lines of $out/$name.log:" >&2
    tail -n 5 "$out/$name.log" | sed 's/^/  /' >&2
    status=1
  fi
  # Once the render client is done, give the nodes a short grace period.
  [ "$name" = render_client ] && deadline=$((SECONDS + 30))
done
cleanup
grep -h "^summary:" "$out/render_client.log" || true
grep -h "HC frames" "$out/node0.log" "$out/node1.log" || true
exit $status
