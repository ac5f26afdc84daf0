#!/usr/bin/env bash
# The cluster on three hosts over ssh (scripts/cluster.sh --hosts runs this): switch node 0 on
# HOST0, switch node 1 on HOST1, the render client on HOSTC, each started by ssh as
# scripts/cluster_rank.sh --rank K (docs/clusters.md) in a work folder of its own on its host.
#
#   scripts/cluster.sh --hosts HOST0,HOST1,HOSTC --scene S [--path P] [--frames N] [--out DIR]
#       [--remote-dir DIR] [--remote-out DIR] [--ssh-config FILE] [extra args as for cluster.sh]
#
# HOST: an ssh destination ([user@]host); the part after @ is the address the other hosts reach it
# at. --remote-dir: the checkout on every host (default: the same path as here; binaries in its
# build/bin, or OCC_BIN's path when set). --remote-out: the work folder on each host (default
# /tmp/occswitch-USER-PID), removed at the end. --ssh-config FILE: ssh -F FILE (default: your ssh
# setup; ssh runs with BatchMode, so keys, not passwords; OCC_SSH_CONNECT_TIMEOUT_S, default 10, its
# ConnectTimeout). Before anything starts each host is
# checked (reachable, the script and binaries there); a fresh cluster key (or --cluster-key-file)
# goes to every host, mode 0600. The nodes pick their ports; this script carries each node's
# HOST:PORT (and a failure's error line, the render client's end) between the hosts' rendezvous
# folders. The logs of all three and the frames come back to --out (default out/cluster_hosts).
# Every process started on any host is stopped on every exit path (the end, a failure, Ctrl-C):
# each runs under ssh -tt, so a closed connection hangs it up, and its pid files are killed too.
set -uo pipefail
source "$(dirname "$0")/lib.sh"
exec 3>&2  # this script's own stderr, for its traps (occ_trap_say)
connect_timeout=${OCC_SSH_CONNECT_TIMEOUT_S:-10}
[[ $connect_timeout =~ ^[1-9][0-9]{0,4}$ ]] ||
  occ_die "OCC_SSH_CONNECT_TIMEOUT_S '$connect_timeout': expected whole seconds, 1 to 99999"

hosts="" scene="" path="walk" frames=60 out="out/cluster_hosts" remote_dir=$here remote_out="" ssh_config=""
key_file="" rest=()
while [ $# -gt 0 ]; do
  case "$1" in
    --hosts|--scene|--path|--frames|--out|--remote-dir|--remote-out|--ssh-config) occ_set "$@"; shift 2 ;;
    --cluster-key-file) occ_need_value "$@"; key_file=$2; shift 2 ;;
    --netns|--link|--window|--record|--pin-nodes|--host-cpus) occ_die "$1 runs on one machine: not with --hosts" ;;
    -h|--help) occ_usage; exit 0 ;;
    --*) occ_need_value "$@"; rest+=("$1" "$2"); shift 2 ;;
    *) occ_unexpected "$1" ;;
  esac
done
IFS=, read -r -a host <<<"$hosts"
[ ${#host[@]} = 3 ] && [ -n "${host[0]}" ] && [ -n "${host[1]}" ] && [ -n "${host[2]}" ] ||
  occ_die "--hosts '$hosts': expected HOST0,HOST1,HOSTC (node 0, node 1, the render client)"
[ -n "$scene" ] || occ_die "--scene is required (e.g. --scene city)"
rbin=${OCC_BIN:-$remote_dir/build/bin}
rout=${remote_out:-/tmp/occswitch-$(id -un)-$$}
role=(node0 node1 render_client)
mkdir -p "$out"
rm -f "$out"/*.log "$out"/frame_*.png "$out"/stats.csv

# Each call its own connection (a rank's ends with it: the rank hangs up).
ssh_cmd=(ssh ${ssh_config:+-F "$ssh_config"} -o BatchMode=yes -o ConnectTimeout="$connect_timeout" -o ControlMaster=no)
ssh_() { timeout 60 "${ssh_cmd[@]}" "$@"; }  # a short call: bounded, so a trap is never held up long
q() { local s; s=$(printf '%q ' "$@"); printf '%s' "${s% }"; }  # words quoted for the remote shell
say() { echo "cluster: $*" >&2; }

pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done
  for k in 0 1 2; do  # whatever still runs there (its pid files: the rank first), then the work folder
    timeout 30 "${ssh_cmd[@]}" "${host[$k]}" "cd $(q "$rout/out") 2>/dev/null &&
      { kill \$(cat *.rank.pid) 2>/dev/null; sleep 0.5; kill \$(cat *.pid) 2>/dev/null; }; rm -rf $(q "$rout")" \
      </dev/null 2>/dev/null &
  done
  wait
}
trap 'occ_trap_say "cluster: interrupted, stopping all processes"; cleanup; exit 130' INT TERM

# 1. Every host answers, has the script and the binaries, and gets its work folder and the key.
[ -n "$key_file" ] || { key_file=$out/cluster.key; occ_make_key "$key_file"; }
for k in 0 1 2; do
  h=${host[$k]}
  err=$(ssh_ "$h" "test -x $(q "$remote_dir/scripts/cluster_rank.sh") || { echo 'no $remote_dir/scripts/cluster_rank.sh (--remote-dir)'; exit 3; }
    for b in switch_node render_client; do test -x $(q "$rbin")/\$b || { echo \"no $rbin/\$b (build it there, or set OCC_BIN)\"; exit 3; }; done
    rm -rf $(q "$rout") && mkdir -p $(q "$rout/rdv") $(q "$rout/out") && (umask 077 && cat >$(q "$rout/cluster.key"))" \
    <"$key_file" 2>&1)
  rc=$?
  [ $rc = 0 ] && continue
  case $rc in
    255) err="unreachable over ssh: ${err##*$'\n'}" ;;
    124) err="no answer over ssh within 60 s" ;;
    *) err=${err##*$'\n'} ;;
  esac
  echo "error: host $h (${role[$k]}): $err" >&2
  cleanup
  exit 1
done

# 2. The three ranks, each under ssh -tt (its output in OUT/ROLE.ssh.log); pids are the ssh clients.
for k in 0 1 2; do
  h=${host[$k]}
  "${ssh_cmd[@]}" -tt "$h" "cd $(q "$remote_dir") && OCC_BIN=$(q "$rbin") OCC_HOST_NAME=$(q "${h##*@}") exec $(q scripts/cluster_rank.sh --rank "$k" \
    --rendezvous "$rout/rdv" --out "$rout/out" --address "${h##*@}" --cluster-key-file "$rout/cluster.key" \
    --scene "$scene" --path "$path" --frames "$frames" "${rest[@]}")" </dev/null >"$out/${role[$k]}.ssh.log" 2>&1 &
  pids+=($!)
done

# 3. The rendezvous between the hosts: FILE from host K to the others, once it is there.
forwarded=()
forward() {  # k file
  local text
  [[ " ${forwarded[*]} " == *" $2 "* ]] && return 0
  text=$(ssh_ "${host[$1]}" "cat $(q "$rout/rdv/$2") 2>/dev/null" </dev/null) && [ -n "$text" ] || return 1
  for j in 0 1 2; do
    [ "$j" = "$1" ] || ssh_ "${host[$j]}" "cat >$(q "$rout/rdv/$2.tmp") && mv $(q "$rout/rdv/$2.tmp") $(q "$rout/rdv/$2")" \
      <<<"$text" || say "could not pass $2 to ${host[$j]}"
  done
  forwarded+=("$2")
}
# The forwarding runs in a subshell of its own while this shell only waits for the render client:
# a Ctrl-C's trap then never interrupts this shell inside a command substitution (bash 5.2 can
# misparse the trap's text there: "unexpected EOF while looking for matching `)'").
forwarder() {
  while kill -0 "${pids[2]}" 2>/dev/null && kill -0 $$ 2>/dev/null; do
    forward 0 node0.addr; forward 1 node1.addr
    forward 0 node0.failed; forward 1 node1.failed; forward 2 render_client.failed
    occ_quiet_sleep 0.3
  done
}
forwarder &
forwarder_pid=$!
pids+=($forwarder_pid)  # (cleanup stops it with the rest)
status=0
wait "${pids[2]}" || status=1
kill $forwarder_pid 2>/dev/null; wait $forwarder_pid 2>/dev/null
forward 2 render_client.done || forward 2 render_client.failed
for k in 0 1; do  # the nodes end with the render client's goodbye (or its failure): waits up to 30 s
  for _ in $(seq 300); do kill -0 "${pids[$k]}" 2>/dev/null || break; sleep 0.1; done
  kill -0 "${pids[$k]}" 2>/dev/null && { say "${role[$k]} on ${host[$k]} still running: stopped"; kill "${pids[$k]}"; }
  wait "${pids[$k]}" || status=1
done

# 4. Logs and frames back here, the hosts cleaned up, the summary.
for k in 0 1 2; do
  timeout 900 "${ssh_cmd[@]}" "${host[$k]}" "tar -C $(q "$rout/out") -cf - --exclude='*.pid' --exclude='*.port' ." </dev/null |
    tar -C "$out" -xf - || say "could not fetch the logs of ${role[$k]} from ${host[$k]}"
done
cleanup
for k in 0 1 2; do
  tr -d '\r' <"$out/${role[$k]}.ssh.log" | grep -E "^(error|cluster_rank|  )" >&2
done
sed -n '/^run (/,/^summary:/p' "$out/render_client.log" 2>/dev/null  # the run table and the summary line
[ $status = 0 ] || echo "error: the cluster on $hosts failed (logs: $out)" >&2
exit $status
