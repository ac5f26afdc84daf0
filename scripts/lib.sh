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
    --no-images|--item-buffer) rvg_only+=("$1"); occ_shift=1 ;;
    --full-sets) common+=("$1"); occ_shift=1 ;;
    --record|--lookahead|--on-node-failure|--occlusion-gate|--two-pass) occ_need_value "$@"; rvg_only+=("$1" "$2") ;;
    --diff-chunk|--adaptive-queries|--hc-order|--occluder-fusion|--sealed|--visibility-hold|--hc-test|--or-raster)
      occ_need_value "$@"; node_only+=("$1" "$2") ;;
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
# tick ten times a second for the whole run, and a fork and exec of sleep(1) each time took 4-5 %
# of a 2-core machine's CPU from the processes they supervise (perf record -a, a cluster run of
# the pipes). Where no FIFO can be made, sleep(1).
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
