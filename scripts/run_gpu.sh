#!/usr/bin/env bash
# The prepared GPU run, in one command with no network and no installs: from the folder
# scripts/gpu_bundle.sh made (copied to a machine with an NVIDIA driver), or from a checkout
# (binaries in build/bin, or OCC_BIN). It checks that GL_RENDERER is a GPU (a software renderer
# such as llvmpipe is refused unless --allow-software), builds the scenes (plant:13 and plant:80:
# the generator is in the binaries; the scene cache keeps them for later runs), and prints one
# table: per scene and viewport (1920x1080, 3840x2160), brute force, frustum culling, CHC and the
# cluster (two switch nodes and the render client: three processes on the one GPU, through
# scripts/cluster.sh), each with its median and p99 frame time in ms (render_ms of the reference
# renderer, frame_interval_ms of the cluster; frame 0 left out), fps (frames / their total time),
# wrong pixels against brute force (frame_diff, on --image-frames frames of the same path drawn
# again with images, so PNG writing never counts as frame time), peak GPU memory (nvidia-smi's
# memory.used during the run, "n/a" without nvidia-smi) and peak host memory (the processes' peak
# RSS, summed over the cluster's three).
#
#   run_gpu.sh [--allow-software] [--quick] [--scenes S,S] [--viewports WxH,WxH] [--frames N]
#              [--image-frames K] [--out DIR] [--cache DIR] [--libs auto|bundled] [--backend B]
#
# --scenes: any --scene specs (default plant:13,plant:80), or a shared scene by its folder
# (ReciprocatingSaw, bim/schependomlaan: the bundle's scenes/, or ../shared/scenes in a checkout).
# --frames N: frames of the walk path that are timed (default 200); --image-frames K (default
# 10): K of them, evenly spaced, drawn with images. --quick (flags after it override it): plant:1
# at 256x256, 12 frames, 3 with images (a test on a software renderer). --out DIR (default
# ./gpu_run): every run's stats.csv and logs, and table.txt. --cache DIR (default OUT/cache): the
# scene cache (plant:80: about 3 GB). --backend B goes to the switch nodes (switch_node --help).
# --libs bundled: the bundle's libglvnd and glibc as well (default auto: only where the machine has
# no libEGL.so.1, or an older glibc).
# When NVIDIA's libEGL_nvidia.so.0 is installed but no EGL vendor file names it, one is written
# into OUT. Exit 1 when a run fails (naming its log), 2 on usage errors.
set -uo pipefail
self=$(cd "$(dirname "$0")" && pwd)
if [ -f "$self/BUILD_INFO" ]; then root=$self bundle=1; else root=$(cd "$self/.." && pwd) bundle=0; fi
for a in "$@"; do
  case "$a" in
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
  esac
done
[ "${1:-}" = --version ] && { echo "run_gpu.sh (occswitch) $(cat "$root/VERSION")"; exit 0; }
if [ $bundle = 1 ]; then BIN=${OCC_BIN:-$root/bin}; else BIN=${OCC_BIN:-$root/build/bin}; fi
cluster=$root/scripts/cluster.sh

usage_error() { echo "error: $* (see run_gpu.sh --help)" >&2; exit 2; }
fail() { echo "error: $*" >&2; exit 1; }
log() { echo "run_gpu: $*" >&2; }

allow_software=0 scenes="plant:13,plant:80" viewports="1920x1080,3840x2160" frames=200 image_frames=10
out=gpu_run cache="" libs=auto backend=""
while [ $# -gt 0 ]; do
  case "$1" in
    --allow-software) allow_software=1; shift ;;
    --quick) scenes=plant:1 viewports=256x256 frames=12 image_frames=3; shift ;;
    --scenes|--viewports|--frames|--image-frames|--out|--cache|--libs|--backend)
      [ $# -ge 2 ] || usage_error "$1 needs a value"
      v=${1#--}; printf -v "${v//-/_}" '%s' "$2"; shift 2 ;;
    *) usage_error "unexpected argument '$1'" ;;
  esac
done
[[ "$frames" =~ ^[0-9]+$ && "$frames" -ge 2 ]] || usage_error "--frames '$frames': expected a whole number >= 2"
[[ "$image_frames" =~ ^[0-9]+$ && "$image_frames" -ge 1 && "$image_frames" -le "$frames" ]] ||
  usage_error "--image-frames '$image_frames': expected 1..--frames"
[[ "$libs" = auto || "$libs" = bundled ]] || usage_error "--libs '$libs': expected auto or bundled"
IFS=, read -ra scene_list <<<"$scenes"
IFS=, read -ra viewport_list <<<"$viewports"
for vp in "${viewport_list[@]}"; do
  [[ "$vp" =~ ^[0-9]+x[0-9]+$ ]] || usage_error "--viewports: '$vp' is not WxH"
done
for b in render_client switch_node frame_diff; do [ -x "$BIN/$b" ] || fail "$BIN/$b not found"; done
[ -x "$cluster" ] || [ -f "$cluster" ] || fail "$cluster not found"
mkdir -p "$out" || fail "cannot create $out"
out=$(cd "$out" && pwd)
cache=${cache:-$out/cache}
mkdir -p "$cache" || fail "cannot create $cache"
start=$SECONDS

# The bundle's libglvnd and glibc where this machine lacks them (the bin/ wrappers read these).
ld_cache=$({ ldconfig -p || /sbin/ldconfig -p; } 2>/dev/null)  # the libraries the loader finds by name
if [ $bundle = 1 ]; then
  have_glibc=$(getconf GNU_LIBC_VERSION 2>/dev/null | awk '{ print $2 }')
  want_glibc=$(cat "$root/lib/glibc/VERSION")
  older=$([ -n "$have_glibc" ] && printf '%s\n%s\n' "$have_glibc" "$want_glibc" | sort -V | head -n 1)
  used="the bundle's"
  if [ "$libs" = bundled ] || ! grep -q 'libEGL\.so\.1 ' <<<"$ld_cache"; then
    export OCC_BUNDLE_GLVND=1
    used+=", its libglvnd"
  fi
  if [ "$libs" = bundled ] || [ -z "$have_glibc" ] || { [ "$older" = "$have_glibc" ] && [ "$have_glibc" != "$want_glibc" ]; }; then
    export OCC_BUNDLE_GLIBC=1
    used+=", its glibc $want_glibc (machine: ${have_glibc:-unknown})"
  fi
  log "bundle $(head -n 1 "$root/BUILD_INFO"); libraries: $used"
fi

# NVIDIA's EGL library without a vendor file naming it: libglvnd would not find it.
vendor_dirs=${__EGL_VENDOR_LIBRARY_DIRS:-/etc/glvnd/egl_vendor.d:/usr/share/glvnd/egl_vendor.d}
nvidia_lib=$(awk '/libEGL_nvidia\.so\.0 / { print $NF; exit }' <<<"$ld_cache")
if [ -n "$nvidia_lib" ]; then
  named=0
  IFS=: read -ra vdirs <<<"$vendor_dirs"
  for d in "${vdirs[@]}"; do grep -qs libEGL_nvidia "$d"/*.json && named=1; done
  if [ $named = 0 ]; then
    mkdir -p "$out/egl_vendor.d"
    printf '{"file_format_version": "1.0.0", "ICD": {"library_path": "%s"}}\n' "$nvidia_lib" >"$out/egl_vendor.d/10_nvidia.json"
    export __EGL_VENDOR_LIBRARY_DIRS=$out/egl_vendor.d:$vendor_dirs
    log "wrote an EGL vendor file for $nvidia_lib ($out/egl_vendor.d)"
  fi
fi

smi=$(command -v nvidia-smi || true)
[ -z "$smi" ] || log "GPU: $("$smi" --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null | head -n 1)"

# The first error line of a log (else its last line).
first_error() { grep -m 1 '^error' "$1" 2>/dev/null || tail -n 1 "$1" 2>/dev/null; }

# The renderer: a GPU, or refused.
mkdir -p "$out/gl_check"
"$BIN/render_client" --scene city:2x2 --path walk:1 --width 64 --height 64 --images off \
  --lod-cache "$cache" --out "$out/gl_check" >"$out/gl_check/log.txt" 2>&1 ||
  fail "no GL context (log: $out/gl_check/log.txt): $(first_error "$out/gl_check/log.txt")"
gl_line=$(grep -m 1 'GL_RENDERER' "$out/gl_check/log.txt")
gl_line=${gl_line#render_client: }
log "$gl_line"
if [[ "$gl_line" == *"software renderer" ]] && [ $allow_software = 0 ]; then
  fail "GL_RENDERER is a software renderer, not a GPU (${gl_line#GL_RENDERER }): is the NVIDIA driver's EGL installed? (--allow-software runs anyway)"
fi

# Peak GPU memory over a run: nvidia-smi sampling into a file.
sampler=""
gpu_start() { [ -z "$smi" ] || { "$smi" --query-gpu=memory.used --format=csv,noheader,nounits -lms 200 >"$1" 2>/dev/null & sampler=$!; }; }
gpu_stop() {
  [ -z "$sampler" ] || { kill "$sampler" 2>/dev/null; wait "$sampler" 2>/dev/null; sampler=""; }
  if [ -n "$smi" ] && [ -s "$1" ]; then awk '$1 + 0 > m { m = $1 + 0 } END { print m }' "$1"; else echo n/a; fi
}
trap 'gpu_stop /dev/null >/dev/null; exit 130' INT TERM

# median p99 fps of COLUMN in a stats.csv, frame 0 left out.
frame_stats() {
  awk -F, -v col="$2" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == col) c = i; next } NR > 2 && c { print $c }' "$1" |
    sort -g | awk '{ v[NR] = $1; s += $1 }
      END { if (NR == 0 || s <= 0) { print "n/a n/a n/a"; exit }
            i = int(NR * 0.99); if (i < NR * 0.99) i++
            printf "%.2f %.2f %.1f\n", v[int((NR + 1) / 2)], v[i], 1000 * NR / s }'
}
peak_rss() { grep -ho 'peak_rss_mb=[0-9]*' "$1" 2>/dev/null | tail -n 1 | cut -d= -f2; }

# run_one KIND DIR PATH IMAGES: KIND none|frustum|chc (reference renderer) or cluster; IMAGES 0|1.
run_one() {
  local kind=$1 d=$2 p=$3 images=$4 rc=0
  local img=(); [ "$images" = 1 ] || img=(--images off)
  mkdir -p "$d"
  if [ "$kind" = cluster ]; then
    local node=(); [ -z "$backend" ] || node=(--backend "$backend")
    OCC_BIN=$BIN OCC_MAX_SECONDS=900 OCC_PORT_WAIT_S=300 "$cluster" --scene "$scene" --path "$p" --width "$w" --height "$h" \
      --lod-cache "$cache" --on-node-failure exit --out "$d" "${img[@]}" "${node[@]}" >"$d/cluster.txt" 2>&1 || rc=$?
    [ $rc = 0 ] || fail "cluster on $scene ${w}x$h failed (logs: $d): $(first_error "$d/cluster.txt")"
  else
    timeout 900 "$BIN/render_client" --scene "$scene" --path "$p" --width "$w" --height "$h" --cull "$kind" \
      --lod-cache "$cache" --out "$d" "${img[@]}" >"$d/log.txt" 2>&1 || rc=$?
    [ "$kind" = none ] && [ "$images" = 0 ] && [ $rc = 0 ] && cp "$d/path.csv" "$cdir/path.csv"
    [ $rc = 0 ] || fail "$kind on $scene ${w}x$h failed (status $rc, log: $d/log.txt): $(first_error "$d/log.txt")"
  fi
}

# A shared scene by its folder's name (--scenes ReciprocatingSaw,bim/schependomlaan): its one glTF file.
if [ $bundle = 1 ]; then scenes_dir=$root/scenes; else scenes_dir=${OCC_SHARED_DIR:-$root/../shared}/scenes; fi
scene_file() {
  local files=()
  [ -d "$scenes_dir/$1" ] && files=("$scenes_dir/$1"/*.gltf "$scenes_dir/$1"/*.glb)
  local f found=""
  for f in "${files[@]}"; do [ -f "$f" ] && found=$f; done
  echo "${found:-$1}"
}

rows=()
for name in "${scene_list[@]}"; do
  scene=$(scene_file "$name")
  t0=$SECONDS
  log "$name: building (or loading from $cache)"
  scene_dir=$out/${name//[:\/]/_}
  mkdir -p "$scene_dir/build"
  "$BIN/render_client" --scene "$scene" --path walk:1 --width 64 --height 64 --images off \
    --lod-cache "$cache" --out "$scene_dir/build" >"$scene_dir/build/log.txt" 2>&1 ||
    fail "$scene: cannot build the scene (log: $scene_dir/build/log.txt): $(first_error "$scene_dir/build/log.txt")"
  log "$name: ready in $((SECONDS - t0)) s ($(grep -m 1 -o '[0-9.]* M triangles' "$scene_dir/build/log.txt"))"
  for vp in "${viewport_list[@]}"; do
    w=${vp%x*} h=${vp#*x}
    cdir=$scene_dir/$vp
    for kind in none frustum chc cluster; do
      log "$name $vp: $kind"
      gpu_start "$cdir/$kind.gpu"
      run_one "$kind" "$cdir/$kind" "walk:$frames" 0
      gpu_mb=$(gpu_stop "$cdir/$kind.gpu")
      if [ "$kind" = none ]; then  # the frames drawn with images: K of the path, evenly spaced, renumbered
        awk -F, -v OFS=, -v n="$frames" -v k="$image_frames" 'BEGIN { s = int(n / k); if (s < 1) s = 1 }
          NR == 1 { print; next } (NR - 2) % s == 0 && c < k { $1 = c++; print }' "$cdir/path.csv" >"$cdir/image_path.csv"
      fi
      run_one "$kind" "$cdir/${kind}_images" "$cdir/image_path.csv" 1
      if [ "$kind" = cluster ]; then
        read -r med p99 fps < <(frame_stats "$cdir/cluster/stats.csv" frame_interval_ms)
        host=0
        for f in render_client node0 node1; do
          v=$(peak_rss "$cdir/cluster/$f.log")
          host=$((host + ${v:-0}))
        done
      else
        read -r med p99 fps < <(frame_stats "$cdir/$kind/stats.csv" render_ms)
        host=$(peak_rss "$cdir/$kind/log.txt")
      fi
      wrong=-
      if [ "$kind" != none ]; then
        "$BIN/frame_diff" "$cdir/none_images" "$cdir/${kind}_images" >"$cdir/$kind.wrong.txt" 2>&1 ||
          fail "frame_diff $kind on $scene $vp failed ($cdir/$kind.wrong.txt): $(tail -n 1 "$cdir/$kind.wrong.txt")"
        wrong=$(tail -n 1 "$cdir/$kind.wrong.txt" | grep -o 'differing_pixels=[0-9]*' | cut -d= -f2)
        rm -f "$cdir/${kind}_images"/frame_*.png
      fi
      case $kind in none) label="brute force" ;; cluster) label="cluster (3 proc)" ;; *) label=$kind ;; esac
      rows+=("$(printf '%-16s %-10s %-17s %9s %9s %8s %9s %8s %8s' "$name" "$vp" "$label" "$med" "$p99" "$fps" "$wrong" "$gpu_mb" "${host:-n/a}")")
    done
    rm -f "$cdir/none_images"/frame_*.png
  done
done

{
  echo "occswitch GPU run $(date -u +%Y-%m-%dT%H:%M:%SZ): $gl_line"
  echo "$frames frames of walk:$frames per row (frame 0 left out of the times); wrong pixels: $image_frames of them against brute force"
  printf '%-16s %-10s %-17s %9s %9s %8s %9s %8s %8s\n' scene viewport method median_ms p99_ms fps wrong_px gpu_mb host_mb
  printf '%s\n' "${rows[@]}"
  echo "total $((SECONDS - start)) s"
} | tee "$out/table.txt"
