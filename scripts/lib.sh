# Sourced by the scripts (bench.sh, cluster.sh, netlab.sh, accuracy_sweep.sh, ...): what their
# argument handling and start-up share. Defines `here` (the checkout) and `BIN` (the binaries'
# folder, OCC_BIN overrides it); usage errors exit 2 with one line naming the flag.
#
#   case "$1" in
#     --scene|--path|--out) occ_set "$@"; shift 2 ;;   # sets $scene, $path, $out
#     -h|--help) occ_usage; exit 0 ;;
#     *) occ_unexpected "$1" ;;
#   esac

here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BIN=${OCC_BIN:-$here/build/bin}
OCC_SCRIPT="scripts/$(basename "$0")"

# --version as the first argument: the script's name and the project's version (the VERSION file).
if [ "${1:-}" = --version ]; then
  echo "$(basename "$0") (occswitch) $(cat "$here/VERSION")"
  exit 0
fi

# The script's header comment (line 2 up to the first line that is not a comment), as help.
occ_usage() { awk 'NR == 1 { next } /^#/ { sub(/^# ?/, ""); print; next } { exit }' "$0"; }

# occ_help_first "$@": -h or --help as the first argument prints the help and exits 0 (--version
# is answered above, when lib.sh is sourced): for scripts that take no flags of their own before
# they install or build anything.
occ_help_first() {
  case "${1:-}" in -h|--help) occ_usage; exit 0 ;; esac
}

occ_die() {
  echo "error: $*" >&2
  exit 2
}

occ_unexpected() { occ_die "unexpected argument '$1' (see $OCC_SCRIPT --help)"; }

# occ_need_value "$@": the flag in $1 must be followed by a value.
occ_need_value() { [ $# -ge 2 ] || occ_die "$1 needs a value (see $OCC_SCRIPT --help)"; }

# occ_set "$@": --some-flag VALUE sets the variable some_flag to VALUE (the caller shifts 2).
occ_set() {
  occ_need_value "$@"
  local name=${1#--}
  printf -v "${name//-/_}" '%s' "$2"
}

# occ_route_flag "$@": a flag of the cluster's processes (cluster.sh, cluster_rank.sh) joins the
# arrays of the processes it is for: rvg_only (the render client), node_only (the switch nodes) or
# common (all three). Sets occ_shift to the words it took (the caller shifts them).
occ_route_flag() {
  occ_shift=2
  case "$1" in
    --images|--on-node-failure|--occlusion|--lookahead) occ_need_value "$@"; rvg_only+=("$1" "$2") ;;
    --coherence|--backend) occ_need_value "$@"; node_only+=("$1" "$2") ;;
    --*) occ_need_value "$@"; common+=("$1" "$2") ;;
    *) occ_unexpected "$1" ;;
  esac
}

# occ_make_key FILE: a fresh random cluster key (64 hex digits), readable by this user only.
occ_make_key() {
  rm -f "$1"
  (umask 077 && head -c 32 /dev/urandom | od -An -tx1 -v | tr -d ' \n' >"$1.tmp" && mv "$1.tmp" "$1") ||
    occ_die "cannot write the cluster key $1"
}

# occ_report_failure NAME WHY LOG: "SCRIPT: NAME WHY (log: LOG):" and the process's own error lines
# (its log's "error:" lines, else its last line), on stderr.
occ_report_failure() {
  local lines
  lines=$(grep -m 3 '^error' "$3" 2>/dev/null) || lines=$(tail -n 1 "$3" 2>/dev/null)
  echo "$(basename "$0" .sh): $1 $2 (log: $3):" >&2
  [ -n "$lines" ] && sed 's/^/  /' <<<"$lines" >&2
}

# occ_quiet_sleep S: sleep without bash's "Killed" line for a background job that a signal ended
# (bash prints it on its own stderr after the next command). A trap can run while stderr is
# redirected like this: it says its line with occ_trap_say, on fd 3 where the script kept its own
# stderr (exec 3>&2 at its start), else on stderr. No process is started: a timed read on a FIFO
# that nothing writes (opened once, its name removed at once), because the supervision loops
# tick ten times a second for the whole run, and a fork and exec of sleep(1) each time took a
# noticeable share of a 2-core machine's CPU from the processes they supervise (perf record -a).
# Where no FIFO can be made, sleep(1).
occ_quiet_sleep() {
  {
    if [ -z "${occ_tick_fd:-}" ]; then
      local fifo
      fifo=$(mktemp -u "${TMPDIR:-/tmp}/occ_tick.XXXXXX") && mkfifo -m 600 "$fifo" && exec {occ_tick_fd}<>"$fifo"
      rm -f "$fifo"
      [ -n "${occ_tick_fd:-}" ] || occ_tick_fd=none
    fi
    if [ "$occ_tick_fd" = none ]; then
      sleep "$1"
    else
      local tick
      read -r -t "$1" -u "$occ_tick_fd" tick
      jobs >/dev/null  # (a builtin does not reap: this says the "Killed" lines here, quietly)
    fi
  } 2>/dev/null
  return 0
}
occ_trap_say() { { echo "$*" >&3; } 2>/dev/null || echo "$*" >&2; }

# occ_require_bins NAME...: each binary must be built in $BIN.
occ_require_bins() {
  local b
  for b; do [ -x "$BIN/$b" ] || occ_die "$BIN/$b not built (run scripts/build.sh)"; done
}

# The one default viewport of every binary and script (the binaries' --width/--height defaults).
OCC_WIDTH=512 OCC_HEIGHT=512

# occ_frames_path PATH FRAMES: walk|orbit|fly get FRAMES frames (walk:FRAMES), other paths stay.
occ_frames_path() {
  case "$1" in walk|orbit|fly) echo "$1:$2" ;; *) echo "$1" ;; esac
}

# CPU groups (scripts/cluster.sh and scripts/limit_table.py --host-cpus): a cgroup whose processes
# share CORES cores of CPU time (a CFS quota per period: OCC_CPU_PERIOD_US, default 2000), so that
# each process of the cluster runs as on a host of its own with that many cores, on one machine:
# none takes time from another, and a single-process render measured the same way gets the same
# machine. A short period keeps that budget steady: with a period much longer than a frame, a
# frame runs unthrottled in bursts and then waits (a heavy p99; docs/results.md). Root and the
# kernel's CPU controller (cgroup v1's cpu hierarchy, or v2 with cpu) needed.
#
# occ_cpu_cores VALUE FLAG: VALUE must be a number of cores, 0.05 up to this machine's CPUs.
occ_cpu_cores() {
  [[ "$1" =~ ^[0-9]*\.?[0-9]+$ ]] && awk -v c="$1" -v n="$(nproc --all)" 'BEGIN { exit !(c >= 0.05 && c <= n) }' ||
    occ_die "$2 '$1': expected a number of cores from 0.05 to $(nproc --all)"
}
# occ_cpu_groups_root: the folder new groups go in (prints it), or exit 2 naming what is missing.
occ_cpu_groups_root() {
  if [ -e /sys/fs/cgroup/cpu/cpu.cfs_quota_us ]; then
    [ -w /sys/fs/cgroup/cpu/cgroup.procs ] || occ_die "--host-cpus: /sys/fs/cgroup/cpu is not writable (run as root)"
    echo /sys/fs/cgroup/cpu
  elif grep -qw cpu /sys/fs/cgroup/cgroup.controllers 2>/dev/null; then
    [ -w /sys/fs/cgroup/cgroup.procs ] || occ_die "--host-cpus: /sys/fs/cgroup is not writable (run as root)"
    grep -qw cpu /sys/fs/cgroup/cgroup.subtree_control || echo +cpu >/sys/fs/cgroup/cgroup.subtree_control ||
      occ_die "--host-cpus: cannot enable the cpu controller in /sys/fs/cgroup/cgroup.subtree_control"
    echo /sys/fs/cgroup
  else
    occ_die "--host-cpus: no cgroup CPU controller on this machine (/sys/fs/cgroup/cpu or cgroup v2's cpu)"
  fi
}
# occ_cpu_group_make DIR [CORES]: a new group DIR (under occ_cpu_groups_root); with CORES, its
# quota (without: a parent of groups, v2 passing the controller on to them).
occ_cpu_group_make() {
  mkdir "$1" || occ_die "--host-cpus: cannot make the CPU group $1"
  if [ -z "${2:-}" ]; then
    [ -e "$1/cgroup.subtree_control" ] && echo +cpu >"$1/cgroup.subtree_control"
    return 0
  fi
  local period=${OCC_CPU_PERIOD_US:-2000} quota
  quota=$(awk -v c="$2" -v p="$period" 'BEGIN { printf "%d", c * p + 0.5 }')
  if [ -e "$1/cpu.cfs_quota_us" ]; then
    echo "$period" >"$1/cpu.cfs_period_us" && echo "$quota" >"$1/cpu.cfs_quota_us"
  else
    echo "$quota $period" >"$1/cpu.max"
  fi || occ_die "--host-cpus: cannot set the CPU quota of $1"
}
# occ_cpu_group_remove DIR...: removes the groups, children first, once their processes have
# ended (within 10 s each).
occ_cpu_group_remove() {
  local g
  for g in "$@"; do
    [ -d "$g" ] || continue
    for _ in $(seq 100); do rmdir "$g" 2>/dev/null && break; sleep 0.1; done
    [ -d "$g" ] && echo "$(basename "$0" .sh): could not remove the CPU group $g (processes still in it)" >&2
  done
  return 0
}
# "${occ_in_cpu_group[@]}" DIR CMD...: runs CMD in group DIR (the same process: its pid is CMD's).
occ_in_cpu_group=(sh -c 'echo $$ >"$0/cgroup.procs" && exec "$@"')
# occ_run_in_cpu_group CORES CMD...: CMD in a group of its own with CORES cores; its exit status.
occ_run_in_cpu_group() {
  local cores=$1 root g rc=0
  shift
  occ_cpu_cores "$cores" --host-cpus
  root=$(occ_cpu_groups_root) || exit 2
  g=$root/occswitch-$$-run
  occ_cpu_group_make "$g" "$cores"
  "${occ_in_cpu_group[@]}" "$g" "$@" || rc=$?
  occ_cpu_group_remove "$g"
  return $rc
}
