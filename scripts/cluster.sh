#!/usr/bin/env bash
# Runs the occlusion-switch cluster on this machine: switch nodes 0 and 1 and the render client
# on 127.0.0.1 with free ports (each node binds one and writes a port file; with
# OCC_START_AT_ONCE=1 on plain loopback the ports are picked here and all three start at once, so
# that their scenes load together). Prints the render client's
# summary, keeps every process's log in the output folder (and its pid in DIR/NAME.pid), and exits
# non-zero if the render client failed, a node failed at start, or anything hung (bounded waits):
# that process is named with its own error line and the others are stopped at once. Ctrl-C stops
# all three.
#
#   scripts/cluster.sh --scene S [--path P] [--frames N] [--out DIR] [--restart-nodes N] [extra args]
#
# A switch node that dies once the render client has shown a frame does not end the run: the
# client degrades (docs/recovery.md) and cluster.sh says so, then starts the node again with the
# same flags on its old port, where the client (and node 1) take it back: --restart-nodes N times
# per node (default 3; 0: never; the first at once, later ones after 2 s). Restarted nodes log
# to DIR/nodeK.restartN.log. The summary says per node when it died (frame, time, status), its
# restarts and from which frame it serves again. Exit 0 when the client finished its path. With
# --on-node-failure exit a node's death ends the run as before.
#
# --path walk|orbit|fly (N frames from --frames, default 60), walk:N, or a CSV file (a missing
# file or an unknown kind is refused before anything starts).
# Extra args reach all three processes (--width W --height H --camera-mode M --pixel-error X --gl B
# ...), except render-client-only ones (--images I --on-node-failure P --occlusion O --lookahead N)
# and node-only ones (--backend B, --coherence N), which go where they belong. OCC_BIN overrides the binaries' folder;
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
# time limit (unless OCC_MAX_SECONDS is set). --record FILE.csv copies the flight (OUT/path.csv,
# every camera shown) there as a path.
# --web [ADDR:]PORT[,tls=CERT.pem:KEY.pem|,tls=self-signed] is the same in a browser: the
# render client serves the page; its URLs, with their tokens, are in render_client.log.
# --node-raster-threads N (default 0): llvmpipe's rasteriser threads in each switch node
# (LP_NUM_THREADS for the nodes only). 0 rasterises on the node's own thread: its work is many
# small passes it waits for (OR flushes, HC box tests), and three processes already fill this
# machine's cores (0 measured faster than 1: docs/results.md). It also keeps the nodes clear of a
# Mesa 22.3 rasteriser-thread race that can corrupt the heap (docs/hard_cases.md).
# --client-raster-threads N|auto (default auto): the render client's llvmpipe rasteriser threads
# (its LP_NUM_THREADS). auto: 0 where the nodes are pinned (below: the client has the other
# cores, and a rasteriser thread of its own would only hand its work over and compete with the
# nodes for theirs; measured faster on two cores, docs/results.md), else $LP_NUM_THREADS, or 1.
# --pin-nodes auto|on|off (default auto: on where this machine has fewer than 4 CPUs): both switch
# nodes run on this process's last CPU (taskset), the render client on any. With three processes
# on two cores the render client, whose frame the user waits for, then keeps a core while the
# nodes work; left to float, a node's thread preempts its rasteriser mid-frame. Light views gain
# most (docs/results.md); heavy ones, where all three are busy anyway, gain nothing. With four
# CPUs or more each process has its own.
# --host-cpus CORES (root): each of the three processes in a CPU cgroup of its own with CORES
# cores of CPU time (scripts/lib.sh), as on three hosts of CORES cores each: none takes time from
# another (the nodes are not pinned, the render client's rasteriser threads as without pinning).
# The groups are removed at exit. scripts/limit_table.py --host-cpus measures the single-process
# renders under the same budget.
# --hosts HOST0,HOST1,HOSTC runs the three processes on three hosts over ssh instead
# (scripts/cluster_hosts.sh --help, docs/clusters.md).
# Membership: every run makes a fresh random cluster key (DIR/cluster.key, mode 0600) and gives
# it to all three processes (--cluster-key-file; docs/security.md), unless --cluster-key-file F
# names one to use instead. With the key every link is TLS 1.3 (encrypted and authenticated).
# --no-key runs the cluster without one (plain TCP, no membership check): for loopback
# measurements of what TLS costs (docs/security.md), never across a network you do not trust.
set -uo pipefail
for a in "$@"; do [ "$a" = --hosts ] && exec "$(dirname "$0")/cluster_hosts.sh" "$@"; done  # three hosts over ssh
source "$(dirname "$0")/lib.sh"
MAX_SECONDS=${OCC_MAX_SECONDS:-900}
exec 3>&2  # this script's own stderr, for its traps (occ_trap_say)

scene="" path="" frames=60 out="out/cluster" link="" netns=0 viewer=0 record="" key_file="" node_threads=0 client_threads=auto restart_nodes=3
pin_nodes=auto host_cpus=""
common=() rvg_only=() node_only=()
while [ $# -gt 0 ]; do
  case "$1" in
    --scene|--path|--frames|--out|--link) occ_set "$@"; shift 2 ;;
    --netns) netns=1; shift ;;
    --cluster-key-file) occ_need_value "$@"; key_file=$2; shift 2 ;;
    --no-key) key_file=none; shift ;;
    --node-raster-threads) occ_need_value "$@"; node_threads=$2; shift 2 ;;
    --client-raster-threads) occ_need_value "$@"; client_threads=$2; shift 2 ;;
    --restart-nodes) occ_need_value "$@"; restart_nodes=$2; shift 2 ;;
    --pin-nodes) occ_need_value "$@"; pin_nodes=$2; shift 2 ;;
    --host-cpus) occ_need_value "$@"; host_cpus=$2; shift 2 ;;
    --window) viewer=1; rvg_only+=("$1"); shift ;;
    --web) occ_need_value "$@"; viewer=1; rvg_only+=("$1" "$2"); shift 2 ;;
    --record) occ_need_value "$@"; record=$2; shift 2 ;;
    -h|--help) occ_usage; exit 0 ;;
    *) occ_route_flag "$@"; shift $occ_shift ;;
  esac
done
[ -n "$scene" ] || occ_die "--scene is required (e.g. --scene city)"
[[ "$node_threads" =~ ^[0-9]+$ ]] && [ "$node_threads" -le 64 ] ||
  occ_die "--node-raster-threads '$node_threads': expected a whole number from 0 to 64"
[ "$client_threads" = auto ] || { [[ "$client_threads" =~ ^[0-9]+$ ]] && [ "$client_threads" -le 64 ]; } ||
  occ_die "--client-raster-threads '$client_threads': expected auto or a whole number from 0 to 64"
[[ "$restart_nodes" =~ ^[0-9]+$ ]] || occ_die "--restart-nodes '$restart_nodes': expected a whole number (0: never)"
# The CPUs this script may use: their count and the last one (the nodes' CPU with --pin-nodes).
read -r cpu_count cpu_last < <(python3 -c 'import os; a = sorted(os.sched_getaffinity(0)); print(len(a), a[-1])')
pin=()
if [ -n "$host_cpus" ]; then
  occ_cpu_cores "$host_cpus" --host-cpus
  [ "$pin_nodes" = on ] && occ_die "--pin-nodes on: not with --host-cpus (each process has CPU time of its own there)"
  pin_nodes=off
  cpu_root=$(occ_cpu_groups_root) || exit 2
fi
case "$pin_nodes" in
  auto) [ "$cpu_count" -ge 2 ] && [ "$cpu_count" -lt 4 ] && command -v taskset >/dev/null && pin=(taskset -c "$cpu_last") ;;
  on)
    [ "$cpu_count" -ge 2 ] || occ_die "--pin-nodes on: needs at least 2 CPUs (this process may use $cpu_count)"
    command -v taskset >/dev/null || occ_die "--pin-nodes on: needs util-linux's taskset"
    pin=(taskset -c "$cpu_last") ;;
  off) ;;
  *) occ_die "--pin-nodes '$pin_nodes': expected auto, on or off" ;;
esac
if [ "$client_threads" = auto ]; then
  client_threads=${LP_NUM_THREADS:-1}
  [ ${#pin[@]} = 0 ] || client_threads=0
fi
[ -z "$host_cpus" ] || echo "cluster: node 0, node 1 and the render client each in a CPU group of $host_cpus cores (--host-cpus), the render client with $client_threads rasteriser threads" >&2
[ ${#pin[@]} = 0 ] || echo "cluster: both switch nodes on CPU $cpu_last, the render client on any of $cpu_count with $client_threads rasteriser threads (--pin-nodes $pin_nodes)" >&2
supervise=1  # --on-node-failure exit: a node's death ends the client, so it ends the run
[[ " ${rvg_only[*]} " == *" --on-node-failure exit "* ]] && supervise=0
if [ $viewer = 1 ]; then
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
rm -f "$out"/*.port "$out"/*.pid "$out"/node?.restart*.log "$out"/frame_*.png
if [ -z "$key_file" ]; then  # a fresh random key per run, readable by this user only
  key_file=$out/cluster.key
  occ_make_key "$key_file"
fi
[ "$key_file" = none ] || common+=(--cluster-key-file "$key_file")
export LP_NUM_THREADS=$client_threads  # the render client's (the nodes get theirs below)

pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done; }
trap 'occ_trap_say "cluster: interrupted, stopping all processes"; cleanup; exit 130' INT TERM

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
  trap 'occ_trap_say "cluster: interrupted, stopping all processes"; exit 130' INT TERM
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

# --host-cpus: a CPU group per process (hg0, hg1, hgc: the prefix that starts a command in it),
# removed at exit once the processes have ended.
hg0=() hg1=() hgc=()
if [ -n "$host_cpus" ]; then
  groups=$cpu_root/occswitch-cluster-$$
  remove_groups() { cleanup; wait 2>/dev/null; occ_cpu_group_remove "$groups"/{node0,node1,render_client} "$groups"; }
  if [ $netns = 1 ]; then trap 'teardown; remove_groups' EXIT; else trap remove_groups EXIT; fi
  occ_cpu_group_make "$groups"
  for g in node0 node1 render_client; do occ_cpu_group_make "$groups/$g" "$host_cpus"; done
  hg0=("${occ_in_cpu_group[@]}" "$groups/node0") hg1=("${occ_in_cpu_group[@]}" "$groups/node1")
  hgc=("${occ_in_cpu_group[@]}" "$groups/render_client")
fi

# The process's own error lines (its log's "error:" lines, else its last line) and where its log is.
report_failure() { occ_report_failure "$1" "$2" "${3:-$out/$1.log}"; }

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

# start_node ID PORT LOG: switch node ID listening on PORT (0: a free one; a restarted node takes
# its old one, where the render client and node 1 look for it), its port in LOG's .port file.
# Sets node_pid; OUT/nodeID.pid says which process it is.
start_node() {
  local ns=("${hg0[@]}" "${in_a[@]}") peer=()
  [ "$1" = 1 ] && ns=("${hg1[@]}" "${in_b[@]}") peer=(--peer "$peer0")
  "${ns[@]}" "${pin[@]}" env LP_NUM_THREADS="$node_threads" "$BIN/switch_node" --id "$1" --scene "$scene" "${peer[@]}" \
    --listen "${listen%:*}:$2" --port-file "${3%.log}.port" "${common[@]}" "${node_only[@]}" >"$3" 2>&1 &
  node_pid=$!
  pids+=($node_pid)
  echo $node_pid >"$out/node$1.pid"
}

# free_port: a port nobody listens on now (loopback), for a node to take.
free_port() {
  python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

if [ -z "$link" ] && [ "$netns" = 0 ] && [ "${OCC_START_AT_ONCE:-0}" = 1 ]; then
  # OCC_START_AT_ONCE=1 (a machine running one cluster at a time: scale_budget.sh): on loopback
  # all three start at once, their ports picked here (a port picked free can be taken by another
  # process before the node listens, so not by default): each loads its scene while the
  # others load theirs (a process that connects retries until its peer listens, within
  # --timeout-ms; a missing cache is built once, the others waiting for it). A node still writes
  # its port file only once it listens, so one that fails at start is named as before.
  p0=$(free_port) p1=$(free_port)
  while [ "$p1" = "$p0" ]; do p1=$(free_port); done
  peer0=$addr_a_from_b:$p0
  start_node 0 "$p0" "$out/node0.log"
  node0_pid=$node_pid
  start_node 1 "$p1" "$out/node1.log"
  node1_pid=$node_pid
  "${hgc[@]}" "$BIN/render_client" --scene "$scene" --path "$path" --out "$out" --connect "127.0.0.1:$p0" \
    --connect "127.0.0.1:$p1" "${common[@]}" "${rvg_only[@]}" >"$out/render_client.log" 2>&1 &
  rvg_pid=$!
  pids+=($rvg_pid)
  echo $rvg_pid >"$out/render_client.pid"
  wait_port "$out/node0.port" $node0_pid node0 >/dev/null || { cleanup; exit 1; }
  wait_port "$out/node1.port" $node1_pid node1 >/dev/null || { cleanup; exit 1; }
else
start_node 0 0 "$out/node0.log"
node0_pid=$node_pid
p0=$(wait_port "$out/node0.port" $node0_pid node0) || { cleanup; exit 1; }
peer0=$addr_a_from_b:$p0
if [ -n "$link" ]; then
  start_relay relay_peer "$peer0" "${in_b[@]}"
  peer0=127.0.0.1:$(wait_port "$out/relay_peer.port" "${pids[-1]}" relay_peer) || { cleanup; exit 1; }
fi
start_node 1 0 "$out/node1.log"
node1_pid=$node_pid
p1=$(wait_port "$out/node1.port" $node1_pid node1) || { cleanup; exit 1; }
c0=$addr_a_from_c:$p0 c1=$addr_b_from_c:$p1
if [ -n "$link" ]; then
  start_relay relay_rvg0 "$c0" "${in_c[@]}"
  c0=127.0.0.1:$(wait_port "$out/relay_rvg0.port" "${pids[-1]}" relay_rvg0) || { cleanup; exit 1; }
  start_relay relay_rvg1 "$c1" "${in_c[@]}"
  c1=127.0.0.1:$(wait_port "$out/relay_rvg1.port" "${pids[-1]}" relay_rvg1) || { cleanup; exit 1; }
fi
"${hgc[@]}" "${in_c[@]}" "$BIN/render_client" --scene "$scene" --path "$path" --out "$out" --connect "$c0" \
  --connect "$c1" "${common[@]}" "${rvg_only[@]}" >"$out/render_client.log" 2>&1 &
rvg_pid=$!
pids+=($rvg_pid)
echo $rvg_pid >"$out/render_client.pid"
fi

# ---- Supervision. A bounded wait for all three (the relays are stopped afterwards). The render
# client failing, or a node failing before the client has shown a frame (or with --on-node-failure
# exit), is reported with the process's own error line and the others are stopped at once (they
# would otherwise wait for it until their --timeout-ms). A node dying later leaves the client
# degraded (docs/recovery.md): the run goes on, and the node is started again on its port while
# --restart-nodes allows (the client's rejoiner takes it back). Once the client is done the nodes
# get up to 30 s to finish; a restarted node that had not rejoined by then is stopped.
status=0
deadline=$((SECONDS + MAX_SECONDS))
declare -A running=([render_client]=$rvg_pid [node0]=$node0_pid [node1]=$node1_pid)
declare -A port=([node0]=$p0 [node1]=$p1) logs=([node0]=$out/node0.log [node1]=$out/node1.log)
declare -A restarts=([node0]=0 [node1]=0) due=() story=()

shown() {  # frames the render client has shown (stats.csv rows)
  local n=0
  [ -f "$out/stats.csv" ] && n=$(($(wc -l <"$out/stats.csv") - 1))
  echo $((n < 0 ? 0 : n))
}

# The frames at which the render client's log says something about node ID (PATTERN: what
# follows the node's address in its line), comma-separated.
client_frames() {  # id pattern
  sed -n "s/^render_client: frame \([0-9]*\): .*switch node $1 (.*$2/\1/p" "$out/render_client.log" | paste -sd, -
}
dropped_pattern=': degraded: .*'

still_running() { for n in render_client node0 node1; do [ -n "${running[$n]:-}" ] && printf ' %s' $n; done; }

stop_all() {
  [ ${#running[@]} -gt 0 ] && echo "cluster: stopping$(still_running)" >&2
  cleanup
  for pid in "${running[@]}"; do wait "$pid" 2>/dev/null; done
  running=() due=()
}

node_died() {  # name status: said; due for a restart (at once, then after 2 s) while restarts are left
  local n=$1 at
  at="at $(date +%T), noticed after frame $(shown)"
  report_failure "$n" "died with status $2 $at$([ -n "${running[render_client]:-}" ] &&
    echo '; the render client goes on without it')" "${logs[$n]}"
  story[$n]+="; died with status $2 at $(date +%T)"
  if [ -z "${running[render_client]:-}" ]; then
    :  # the path has ended
  elif [ "${restarts[$n]}" -lt "$restart_nodes" ]; then
    due[$n]=$((SECONDS + (restarts[$n] > 0 ? 2 : 0)))
  else
    echo "cluster: $n is not started again (--restart-nodes $restart_nodes)" >&2
  fi
}

restart_node() {  # name: the same flags, its old port, a log of its own
  local n=$1 k=$((restarts[$1] + 1))
  restarts[$n]=$k
  unset "due[$n]"
  logs[$n]=$out/$n.restart$k.log
  start_node "${n#node}" "${port[$n]}" "${logs[$n]}"
  running[$n]=$node_pid
  echo "cluster: restarting $n on port ${port[$n]} with the same flags ($k of $restart_nodes; log: ${logs[$n]})" >&2
  story[$n]+="; restarted ($k of $restart_nodes)"
}

client_done() {  # status: a failure stops everything; else restarted nodes that never rejoined stop
  due=()
  if [ "$1" -ne 0 ]; then
    report_failure render_client "exited with status $1"
    status=1
    stop_all
    return
  fi
  [ $deadline -gt $((SECONDS + 30)) ] && deadline=$((SECONDS + 30))
  for n in node0 node1; do
    [ -n "${running[$n]:-}" ] && [ "${restarts[$n]}" -gt 0 ] && ! grep -q "resync at frame" "${logs[$n]}" || continue
    kill "${running[$n]}" 2>/dev/null
    wait "${running[$n]}" 2>/dev/null
    unset "running[$n]"
    story[$n]+="; the path ended before it rejoined: stopped"
  done
}

while [ ${#running[@]} -gt 0 ]; do
  for name in render_client node0 node1; do
    pid=${running[$name]:-}
    if [ -z "$pid" ]; then
      [ -n "${due[$name]:-}" ] && [ $SECONDS -ge "${due[$name]}" ] && restart_node $name
      continue
    fi
    kill -0 "$pid" 2>/dev/null && continue
    { wait "$pid"; } 2>/dev/null  # (not bash's own "Killed" line)
    rc=$?
    unset "running[$name]"
    if [ $name = render_client ]; then
      client_done $rc
    elif [ $rc -ne 0 ] && [ $supervise = 1 ] && [ "$(shown)" -gt 0 ] &&
         { [ -n "${running[render_client]:-}" ] || [ -n "$(client_frames "${name#node}" "$dropped_pattern")" ]; }; then
      node_died $name $rc  # (or the client dropped it, and has finished since)
    elif [ $rc -ne 0 ]; then
      report_failure "$name" "exited with status $rc" "${logs[$name]}"
      status=1
      stop_all
    fi
    [ ${#running[@]} -gt 0 ] || break
  done
  [ ${#running[@]} -gt 0 ] || break
  if [ $SECONDS -ge $deadline ]; then
    echo "error:$(still_running) still running after the deadline: killed" >&2
    status=1
    stop_all
    break
  fi
  occ_quiet_sleep 0.1  # (no "Killed" line from bash for a node killed by a signal)
done
cleanup
# The render client's table (from its "run (" title) and the key=value summary line after it.
sed -n '/^run (/,/^summary:/p' "$out/render_client.log"
grep -hE "HC frames|occlusion back end" "$out/node0.log" "$out/node1.log" || true
# What supervision did, per node that died: its deaths (status, time), restarts, and the frames
# at which the render client dropped it and took it back (its own log lines).
for n in node0 node1; do
  [ -n "${story[$n]:-}" ] || continue
  dropped=$(client_frames "${n#node}" "$dropped_pattern") back=$(client_frames "${n#node}" ') is back$')
  story[$n]+="; the render client dropped it at frame ${dropped:-?}"
  story[$n]+=$([ -n "$back" ] && echo " and took it back at frame $back" || echo ", it did not serve again")
  echo "cluster: $n${story[$n]#;}"
done
[ ${#story[@]} -gt 0 ] && grep -h "^modes:" "$out/render_client.log"
if [ -n "$record" ] && [ -s "$out/path.csv" ]; then
  cp "$out/path.csv" "$record" && echo "cluster: the cameras shown are in $record (replay: --path $record)"
fi
exit $status
