#!/usr/bin/env bash
# Runs the occlusion-switch cluster on this machine: switch nodes 0 and 1 and the render client
# on 127.0.0.1 with ephemeral ports (port files, no fixed ports). Prints the render client's
# summary, keeps every process's log in the output folder, and exits non-zero if any process
# failed or hung (bounded waits): the first process to fail is named with its own error line and
# the others are stopped at once. Ctrl-C stops all three.
#
#   scripts/cluster.sh --scene S [--path P] [--frames N] [--out DIR] [extra args]
#
# --path walk|orbit|fly (N frames from --frames, default 60), walk:N, or a CSV file (a missing
# file or an unknown kind is refused before anything starts). --lookahead N (render client,
# default 2): cameras sent ahead, docs/latency.md.
# Extra args reach all three processes (--width W --height H --camera-mode M --full-sets --gl B
# --arity ...), except render-client-only ones (--no-images --item-buffer --lookahead N --on-node-failure P
# --occlusion-gate G --two-pass T) and node-only ones
# (--diff-chunk B, --adaptive-queries, --hc-order, --occluder-fusion, --query-budget,
# --occluder-pixels-per-triangle, --visibility-hold, --leaf-test, --leaf-test-below, --hc-test), which go where they belong. OCC_BIN overrides the binaries' folder;
# OCC_MAX_SECONDS (default 900) bounds the whole run; OCC_PORT_WAIT_S (default 60) each node's start.
# --link DELAY_MS:RATE_MBIT[:JITTER_MS] routes every link (render client <-> each node, node 1 ->
# node 0) through a link_relay that adds that one-way delay, jitter and bandwidth cap per
# direction (user-space: the kernel here has no netem). Relay logs go to the output folder.
# --netns (root only) puts node 0, node 1 and the render client in three network namespaces of
# their own, joined by veth pairs (10.77.1.0/30 node0-client, 10.77.2.0/30 node1-client,
# 10.77.3.0/30 node0-node1); with --link the rate is a tc tbf qdisc on every veth and the delay a
# link_relay on the connecting side. Namespaces, veths and qdiscs are removed at exit, also on
# Ctrl-C or failure.
# --window shows the frames in an X11 window ($DISPLAY) and lets you drive (render_client --help;
# keys: W/A/S/D/Q/E move, arrows or drag look, Shift faster, wheel speed, F walk/fly, R reset,
# P screenshot, O culling overlay, Esc quits). Without --path you drive from the start; with --path the path plays
# and any movement key takes over. It implies --camera-mode latest (unless given) and no overall
# time limit (unless OCC_MAX_SECONDS is set). --record FILE.csv saves the flight as a path.
# --node-raster-threads N (default 0): llvmpipe's rasteriser threads in each switch node
# (LP_NUM_THREADS for the nodes only; the render client keeps $LP_NUM_THREADS, default 1). 0
# rasterises on the node's own thread: its work is many small passes it waits for (OR flushes,
# HC box tests), and three processes already fill this machine's cores. Duplex orbit 512^2,
# paired runs: frame interval 0.92-0.98x against 1 (docs/results.md). It also keeps the nodes
# clear of a Mesa 22.3 rasteriser-thread race that can corrupt the heap (docs/hard_cases.md).
# Membership: every run makes a fresh random cluster key (DIR/cluster.key, mode 0600) and gives
# it to all three processes (--cluster-key-file; docs/security.md), unless --cluster-key-file F
# names one to use instead.
set -uo pipefail
source "$(dirname "$0")/lib.sh"
MAX_SECONDS=${OCC_MAX_SECONDS:-900}

scene="" path="" frames=60 out="out/cluster" link="" netns=0 window=0 key_file="" node_threads=0
common=() rvg_only=() node_only=()
while [ $# -gt 0 ]; do
  case "$1" in
    --scene|--path|--frames|--out|--link) occ_set "$@"; shift 2 ;;
    --netns) netns=1; shift ;;
    --cluster-key-file) occ_need_value "$@"; key_file=$2; shift 2 ;;
    --node-raster-threads) occ_need_value "$@"; node_threads=$2; shift 2 ;;
    --no-images|--item-buffer) rvg_only+=("$1"); shift ;;
    --window) window=1; rvg_only+=("$1"); shift ;;
    --record) occ_need_value "$@"; rvg_only+=("$1" "$2"); shift 2 ;;
    --lookahead|--on-node-failure|--occlusion-gate|--two-pass) occ_need_value "$@"; rvg_only+=("$1" "$2"); shift 2 ;;
    --diff-chunk|--adaptive-queries|--hc-order|--occluder-fusion|--query-budget|--occluder-pixels-per-triangle|--visibility-hold|--leaf-test|--leaf-test-below|--hc-test) occ_need_value "$@"; node_only+=("$1" "$2"); shift 2 ;;
    --full-sets) common+=("$1"); shift ;;
    -h|--help) occ_usage; exit 0 ;;
    --*) occ_need_value "$@"; common+=("$1" "$2"); shift 2 ;;
    *) occ_unexpected "$1" ;;
  esac
done
[ -n "$scene" ] || occ_die "--scene is required (e.g. --scene city)"
[[ "$node_threads" =~ ^[0-9]+$ ]] && [ "$node_threads" -le 64 ] ||
  occ_die "--node-raster-threads '$node_threads': expected a whole number from 0 to 64"
if [ $window = 1 ]; then
  [ -n "$path" ] || path=interactive
  [[ " ${common[*]} " == *" --camera-mode "* ]] || common+=(--camera-mode latest)
  MAX_SECONDS=${OCC_MAX_SECONDS:-31536000}
fi
[ -n "$path" ] || path=walk
path=$(occ_frames_path "$path" "$frames")
# A missing path file or an unknown kind fails now, not after both nodes have loaded the scene
# (the render client checks the file's contents as soon as it starts).
case "$path" in
  interactive|orbit:*|walk:*|fly:*) ;;
  *:*) [ -e "$path" ] || occ_die "--path '$path': unknown kind '${path%%:*}' (expected orbit:N, walk:N, fly:N or a CSV file)" ;;
  *) [ -r "$path" ] || occ_die "--path '$path': cannot open camera path file" ;;
esac
relay_args=()
if [ -n "$link" ]; then
  IFS=: read -r l_delay l_rate l_jitter <<<"$link"
  [[ "$l_delay" =~ ^[0-9.]+$ && "$l_rate" =~ ^[0-9.]+$ && "${l_jitter:-0}" =~ ^[0-9.]+$ ]] ||
    occ_die "--link '$link': expected DELAY_MS:RATE_MBIT[:JITTER_MS] (numbers)"
  relay_args=(--delay-ms "$l_delay" --rate-mbit "$l_rate" --jitter-ms "${l_jitter:-0}")
fi
occ_require_bins switch_node render_client $([ -n "$link" ] && echo link_relay)
mkdir -p "$out"
rm -f "$out"/*.port "$out"/frame_*.png
if [ -z "$key_file" ]; then  # a fresh random key per run, readable by this user only
  key_file=$out/cluster.key
  rm -f "$key_file"
  (umask 077 && head -c 32 /dev/urandom | od -An -tx1 -v | tr -d ' \n' >"$key_file") ||
    occ_die "cannot write the cluster key $key_file"
fi
common+=(--cluster-key-file "$key_file")
export LP_NUM_THREADS=${LP_NUM_THREADS:-1}

pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done; }
trap 'echo "cluster: interrupted, stopping all processes" >&2; cleanup; exit 130' INT TERM

# Where each process runs and how the others reach it.
in_a=() in_b=() in_c=() listen=127.0.0.1:0 addr_a_from_c=127.0.0.1 addr_b_from_c=127.0.0.1 addr_a_from_b=127.0.0.1
if [ $netns = 1 ]; then
  [ "$(id -u)" = 0 ] || occ_die "--netns needs root (network namespaces and veth pairs)"
  command -v ip >/dev/null || occ_die "--netns needs iproute2's ip"
  tag="occ$$"
  ns_a=${tag}a ns_b=${tag}b ns_c=${tag}c
  teardown() {
    cleanup
    wait 2>/dev/null
    for ns in $ns_a $ns_b $ns_c; do ip netns del "$ns" 2>/dev/null; done  # takes its veths and qdiscs
  }
  trap teardown EXIT
  trap 'echo "cluster: interrupted, stopping all processes" >&2; exit 130' INT TERM
  veth() {  # NS1 IF1 ADDR1 NS2 IF2 ADDR2
    ip link add "$2" type veth peer name "$5" &&
    ip link set "$2" netns "$1" && ip link set "$5" netns "$4" &&
    ip -n "$1" addr add "$3/30" dev "$2" && ip -n "$4" addr add "$6/30" dev "$5" &&
    ip -n "$1" link set "$2" up && ip -n "$4" link set "$5" up || return 1
    if [ -n "$link" ] && [ "$l_rate" != 0 ]; then
      for end in "$1 $2" "$4 $5"; do
        set -- $end
        ip netns exec "$1" tc qdisc add dev "$2" root tbf rate "${l_rate}mbit" burst 64kb latency 200ms || return 1
      done
    fi
  }
  { for ns in $ns_a $ns_b $ns_c; do ip netns add "$ns" && ip -n "$ns" link set lo up || exit 1; done
    veth $ns_a ${tag}ac 10.77.1.1 $ns_c ${tag}ca 10.77.1.2 &&
    veth $ns_b ${tag}bc 10.77.2.1 $ns_c ${tag}cb 10.77.2.2 &&
    veth $ns_a ${tag}ab 10.77.3.1 $ns_b ${tag}ba 10.77.3.2; } ||
    { echo "error: --netns: could not set up namespaces and veth pairs" >&2; exit 1; }
  in_a=(ip netns exec $ns_a) in_b=(ip netns exec $ns_b) in_c=(ip netns exec $ns_c)
  listen=0.0.0.0:0 addr_a_from_c=10.77.1.1 addr_b_from_c=10.77.2.1 addr_a_from_b=10.77.3.1
  # The kernel links carry the rate; relays add only the delay.
  [ -n "$link" ] && relay_args=(--delay-ms "$l_delay" --jitter-ms "${l_jitter:-0}")
fi

# The process's own error lines (its log's "error:" lines, else its last line) and where its log is.
report_failure() {  # name why
  local lines
  lines=$(grep -m 3 '^error' "$out/$1.log" 2>/dev/null) || lines=$(tail -n 1 "$out/$1.log" 2>/dev/null)
  echo "cluster: $1 $2 (log: $out/$1.log):" >&2
  [ -n "$lines" ] && sed 's/^/  /' <<<"$lines" >&2
}

wait_port() {  # file pid name (OCC_PORT_WAIT_S, default 60: big scenes load and build LODs first)
  for _ in $(seq 1 $((${OCC_PORT_WAIT_S:-60} * 10))); do
    [ -s "$1" ] && { cat "$1"; return 0; }
    if ! kill -0 "$2" 2>/dev/null; then
      report_failure "$3" "exited before listening"
      return 1
    fi
    sleep 0.1
  done
  echo "error: $3 did not write its port file within ${OCC_PORT_WAIT_S:-60} s (set OCC_PORT_WAIT_S)" >&2; return 1
}

# start_relay NAME TARGET [PREFIX...]: a link_relay in front of TARGET (HOST:PORT), listening on
# 127.0.0.1 (inside the connecting side's namespace with --netns); its port goes to NAME.port.
start_relay() {
  local name=$1 target=$2
  shift 2
  "$@" "$BIN/link_relay" --target "$target" --port-file "$out/$name.port" "${relay_args[@]}" >"$out/$name.log" 2>&1 &
  pids+=($!)
}

"${in_a[@]}" env LP_NUM_THREADS="$node_threads" "$BIN/switch_node" --id 0 --scene "$scene" --listen "$listen" --port-file "$out/node0.port" \
  "${common[@]}" "${node_only[@]}" >"$out/node0.log" 2>&1 &
node0_pid=$!
pids+=($node0_pid)
p0=$(wait_port "$out/node0.port" $node0_pid node0) || { cleanup; exit 1; }
peer0=$addr_a_from_b:$p0
if [ -n "$link" ]; then
  start_relay relay_peer "$peer0" "${in_b[@]}"
  peer0=127.0.0.1:$(wait_port "$out/relay_peer.port" "${pids[-1]}" relay_peer) || { cleanup; exit 1; }
fi
"${in_b[@]}" env LP_NUM_THREADS="$node_threads" "$BIN/switch_node" --id 1 --scene "$scene" --peer "$peer0" --listen "$listen" --port-file "$out/node1.port" \
  "${common[@]}" "${node_only[@]}" >"$out/node1.log" 2>&1 &
node1_pid=$!
pids+=($node1_pid)
p1=$(wait_port "$out/node1.port" $node1_pid node1) || { cleanup; exit 1; }
c0=$addr_a_from_c:$p0 c1=$addr_b_from_c:$p1
if [ -n "$link" ]; then
  start_relay relay_rvg0 "$c0" "${in_c[@]}"
  c0=127.0.0.1:$(wait_port "$out/relay_rvg0.port" "${pids[-1]}" relay_rvg0) || { cleanup; exit 1; }
  start_relay relay_rvg1 "$c1" "${in_c[@]}"
  c1=127.0.0.1:$(wait_port "$out/relay_rvg1.port" "${pids[-1]}" relay_rvg1) || { cleanup; exit 1; }
fi
"${in_c[@]}" "$BIN/render_client" --scene "$scene" --path "$path" --out "$out" --connect "$c0" \
  --connect "$c1" "${common[@]}" "${rvg_only[@]}" >"$out/render_client.log" 2>&1 &
rvg_pid=$!
pids+=($rvg_pid)

# Bounded wait for all three (the relays are stopped afterwards). The first process to fail is
# reported with its own error line and the others are stopped at once (they would otherwise wait
# for it until their --timeout-ms); once the render client is done the nodes get 30 s to finish.
status=0
deadline=$((SECONDS + MAX_SECONDS))
declare -A running=([render_client]=$rvg_pid [node0]=$node0_pid [node1]=$node1_pid)
while [ ${#running[@]} -gt 0 ]; do
  for name in render_client node0 node1; do
    pid=${running[$name]:-}
    [ -n "$pid" ] && ! kill -0 "$pid" 2>/dev/null || continue
    wait "$pid"; rc=$?
    unset "running[$name]"
    [ "$name" = render_client ] && [ $deadline -gt $((SECONDS + 30)) ] && deadline=$((SECONDS + 30))
    if [ $rc -ne 0 ]; then
      report_failure "$name" "exited with status $rc"
      status=1
      if [ ${#running[@]} -gt 0 ]; then
        echo "cluster: stopping$(for n in render_client node0 node1; do [ -n "${running[$n]:-}" ] && printf ' %s' $n; done)" >&2
        cleanup
        for pid in "${running[@]}"; do wait "$pid" 2>/dev/null; done
        running=()
      fi
      break
    fi
  done
  [ ${#running[@]} -gt 0 ] || break
  if [ $SECONDS -ge $deadline ]; then
    echo "error:$(for n in render_client node0 node1; do [ -n "${running[$n]:-}" ] && printf ' %s' $n; done) still running after the deadline: killed" >&2
    cleanup; status=1
    for pid in "${running[@]}"; do wait "$pid" 2>/dev/null; done
    break
  fi
  sleep 0.1
done
cleanup
grep -h "^summary:" "$out/render_client.log" || true
grep -hE "HC frames|HC test" "$out/node0.log" "$out/node1.log" || true
exit $status
