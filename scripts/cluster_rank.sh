#!/usr/bin/env bash
# One process of the occlusion-switch cluster under a job launcher: start the same command as three
# tasks (`mpirun -np 3`, `srun -n 3`) and each takes its role from the launcher's rank variable
# (OMPI_COMM_WORLD_RANK, PMIX_RANK, PMI_RANK, SLURM_PROCID; --rank N overrides): rank 0 is switch
# node 0, rank 1 switch node 1, rank 2 the render client. No MPI library is involved: the launcher
# only starts the processes, they meet through a rendezvous folder that every rank sees (a shared
# file system across hosts) and talk TCP as ever (docs/clusters.md).
#
#   mpirun -np 3 scripts/cluster_rank.sh --rendezvous DIR --scene S [--path P] [--frames N]
#                [--out DIR] [--address HOST] [--wait S] [extra args as for scripts/cluster.sh]
#   srun -n 3 scripts/cluster_rank.sh --rendezvous DIR ...
#
# The rendezvous: each node writes HOST:PORT to DIR/JOB/nodeK.addr once it listens (JOB: the
# launcher's job id, so a folder can serve many jobs; DIR itself without one, then give a fresh
# folder per run); node 1 waits for node 0's, the render client for both, each for at most --wait
# seconds (default 300: big scenes load first). Rank 0 makes a fresh cluster key there
# (DIR/JOB/cluster.key, mode 0600) unless --cluster-key-file F names one every rank can read.
# --address HOST: how the other ranks reach this one (default: this host's first address from
# `hostname -I`, else its name); the nodes listen on 127.0.0.1 when it is a loopback address, else
# on every interface. A rank whose process fails writes DIR/JOB/ROLE.failed (its host and error
# line): the ranks waiting for it stop at once with that line, and the nodes stop when the render
# client failed (mpirun stops the job anyway when a rank exits non-zero; srun without
# --kill-on-bad-exit does not). A node that dies once it has served does not end its rank: the
# render client degrades (docs/recovery.md) and the rank starts the node again on its port with
# the same flags, --restart-nodes N times (default 3; 0: never), as scripts/cluster.sh does; the
# restarted node logs to OUT/ROLE.restartN.log, OUT/ROLE.pid names the process. Each rank logs to
# OUT/ROLE.log (default out/cluster_rank, on its own host); the render client's frames and
# stats.csv go to OUT; rank 2 prints the summary. --node-raster-threads N as in scripts/cluster.sh.
set -uo pipefail
source "$(dirname "$0")/lib.sh"

rendezvous="" scene="" path="walk" frames=60 out="out/cluster_rank" address="" wait=300 rank="" key_file=""
restart_nodes=3 node_threads=0
common=() rvg_only=() node_only=()
while [ $# -gt 0 ]; do
  case "$1" in
    --rendezvous|--scene|--path|--frames|--out|--address|--wait|--rank|--restart-nodes) occ_set "$@"; shift 2 ;;
    --cluster-key-file) occ_need_value "$@"; key_file=$2; shift 2 ;;
    --node-raster-threads) occ_need_value "$@"; node_threads=$2; shift 2 ;;
    --window|--netns|--link|--pin-nodes|--host-cpus) occ_die "$1 is a scripts/cluster.sh option (one machine)" ;;
    -h|--help) occ_usage; exit 0 ;;
    *) occ_route_flag "$@"; shift $occ_shift ;;
  esac
done
[ -n "$rendezvous" ] || occ_die "--rendezvous DIR is required (a folder every rank sees)"
[ -n "$scene" ] || occ_die "--scene is required (e.g. --scene city)"
[[ "$wait" =~ ^[0-9]+$ ]] || occ_die "--wait '$wait': expected a whole number of seconds"
[[ "$node_threads" =~ ^[0-9]+$ ]] && [ "$node_threads" -le 64 ] ||
  occ_die "--node-raster-threads '$node_threads': expected a whole number from 0 to 64"
[[ "$restart_nodes" =~ ^[0-9]+$ ]] || occ_die "--restart-nodes '$restart_nodes': expected a whole number (0: never)"
rank=${rank:-${OMPI_COMM_WORLD_RANK:-${PMIX_RANK:-${PMI_RANK:-${SLURM_PROCID:-}}}}}
size=${OMPI_COMM_WORLD_SIZE:-${PMI_SIZE:-${SLURM_NTASKS:-3}}}
[ -n "$rank" ] || occ_die "no rank: start it with mpirun -np 3 or srun -n 3 (OMPI_COMM_WORLD_RANK, PMIX_RANK," \
  "PMI_RANK or SLURM_PROCID), or give --rank 0|1|2"
[[ "$rank" =~ ^[012]$ ]] && [ "$size" = 3 ] ||
  occ_die "rank $rank of $size: the cluster is exactly 3 ranks (mpirun -np 3, srun -n 3)"
role=$([ "$rank" = 2 ] && echo render_client || echo "node$rank")
job=${OMPI_MCA_ess_base_jobid:-${PMIX_NAMESPACE:-${SLURM_JOB_ID:+slurm-$SLURM_JOB_ID.${SLURM_STEP_ID:-0}}}}
rdv=$rendezvous${job:+/$job}
[ -n "$address" ] || address=$(hostname -I 2>/dev/null | awk '{print $1}')
[ -n "$address" ] || address=$(hostname)
case "$address" in 127.*|localhost|::1) listen=127.0.0.1:0 ;; *) listen=0.0.0.0:0 ;; esac
host=${OCC_HOST_NAME:-$(hostname)}  # (scripts/cluster_hosts.sh names it by its ssh address)
tag="$(basename "$0" .sh) $rank ($role on $host)"
path=$(occ_frames_path "$path" "$frames")
occ_require_bins switch_node render_client
mkdir -p "$out" "$rdv" || occ_die "cannot make the folders $out and $rdv"
log=$out/$role.log
# llvmpipe's rasteriser threads: the render client keeps $LP_NUM_THREADS (default 1), the nodes
# get --node-raster-threads (default 0), as with scripts/cluster.sh (its header says why).
export LP_NUM_THREADS=${LP_NUM_THREADS:-1}
[ "$rank" = 2 ] || export LP_NUM_THREADS=$node_threads

child=""
echo $$ >"$out/$role.rank.pid"  # (scripts/cluster_hosts.sh stops a rank by it)
trap '[ -n "$child" ] && kill "$child" 2>/dev/null; exit 143' TERM INT HUP  # (HUP: its ssh -tt connection closed)

# This rank's process failed: say so here and in the rendezvous, for the ranks that wait for it.
fail() {  # why
  occ_report_failure "$role on $host" "$1" "$log"
  { echo "$role on $host $1:"; grep -m 3 '^error' "$log" 2>/dev/null || tail -n 1 "$log" 2>/dev/null; } \
    >"$rdv/$role.failed.tmp" && mv "$rdv/$role.failed.tmp" "$rdv/$role.failed"
  exit 1
}

# The HOST:PORT that node K published, waiting at most --wait seconds (at once if it failed).
address_of() {  # node-id
  local f=$rdv/node$1.addr
  for _ in $(seq 1 $((wait * 10))); do
    [ -s "$f" ] && { cat "$f"; return 0; }
    if [ -e "$rdv/node$1.failed" ]; then
      echo "error: $tag: $(head -n 1 "$rdv/node$1.failed")" >&2
      sed 1d "$rdv/node$1.failed" | sed 's/^/  /' >&2
      return 1
    fi
    sleep 0.1
  done
  echo "error: $tag: node$1 did not publish its address in $rdv within $wait s (--wait)" >&2
  return 1
}

if [ -z "$key_file" ]; then
  key_file=$rdv/cluster.key
  [ "$rank" = 0 ] && occ_make_key "$key_file"  # before node 0 publishes: the others find it then
fi
common+=(--cluster-key-file "$key_file")

if [ "$rank" = 2 ]; then
  a0=$(address_of 0) && a1=$(address_of 1) || exit 1
  echo "$tag: switch nodes at $a0 and $a1" >&2
  "$BIN/render_client" --scene "$scene" --path "$path" --out "$out" --connect "$a0" --connect "$a1" \
    "${common[@]}" "${rvg_only[@]}" >"$log" 2>&1 &
  child=$!
  echo $child >"$out/$role.pid"
  wait $child; rc=$?
  [ $rc = 0 ] || fail "exited with status $rc"
  touch "$rdv/render_client.done"
  grep -hE "^(summary|modes):" "$log"
  exit 0
fi

peer=()
if [ "$rank" = 1 ]; then
  a0=$(address_of 0) || exit 1
  peer=(--peer "$a0")
fi
# start_node PORT LOG: this rank's switch node on PORT (0: a free one), its port in LOG's .port file.
start_node() {
  rm -f "${2%.log}.port"
  "$BIN/switch_node" --id "$rank" --scene "$scene" "${peer[@]}" --listen "${listen%:*}:$1" \
    --port-file "${2%.log}.port" "${common[@]}" "${node_only[@]}" >"$2" 2>&1 &
  child=$!
  echo $child >"$out/$role.pid"
}
start_node 0 "$log"
for _ in $(seq 1 $((wait * 10))); do
  [ -s "$out/$role.port" ] && break
  kill -0 $child 2>/dev/null || { wait $child; fail "exited before listening"; }
  sleep 0.1
done
[ -s "$out/$role.port" ] || { kill $child; fail "did not listen within $wait s (--wait)"; }
port=$(cat "$out/$role.port")
echo "$address:$port" >"$rdv/$role.addr.tmp" && mv "$rdv/$role.addr.tmp" "$rdv/$role.addr"
echo "$tag: listening at $address:$port" >&2

# Until the node ends (the render client's goodbye). A node that dies once it has served is
# started again on its port with the same flags (--restart-nodes, as scripts/cluster.sh does): the
# render client, degraded meanwhile, takes it back. Stopped when the render client failed, or
# when it finished while a restarted node had not rejoined.
restarts=0
while :; do
  while kill -0 $child 2>/dev/null; do
    if [ -e "$rdv/render_client.failed" ] ||
       { [ -e "$rdv/render_client.done" ] && [ $restarts -gt 0 ] && ! grep -q "resync at frame" "$log"; }; then
      kill $child
      echo "$tag: the render client $([ -e "$rdv/render_client.failed" ] && echo failed || echo finished): stopped" >&2
      break
    fi
    occ_quiet_sleep 0.2
  done
  { wait $child; } 2>/dev/null
  rc=$?
  client_ended=$([ -e "$rdv/render_client.failed" ] || [ -e "$rdv/render_client.done" ] && echo 1)
  if [ $rc != 0 ] && [ -z "$client_ended" ] && grep -q ": connected:" "$out/$role.log"; then
    occ_report_failure "$role on $host" "died with status $rc; the render client goes on without it" "$log"
    [ $restarts -lt "$restart_nodes" ] || { echo "$tag: not started again (--restart-nodes $restart_nodes)" >&2; break; }
    restarts=$((restarts + 1))
    [ $restarts -gt 1 ] && sleep 2
    log=$out/$role.restart$restarts.log
    echo "$tag: restarting on port $port with the same flags ($restarts of $restart_nodes; log: $log)" >&2
    start_node "$port" "$log"
    continue
  fi
  [ $rc = 0 ] || [ -n "$client_ended" ] || fail "exited with status $rc"
  [ -e "$rdv/render_client.done" ] && exit 0
  exit $rc
done
# No restarts left: the render client goes on degraded; this rank ends with it.
while [ ! -e "$rdv/render_client.done" ] && [ ! -e "$rdv/render_client.failed" ]; do sleep 0.5; done
exit 0
