#!/usr/bin/env bash
# Puts into one folder everything a bare x86-64 Linux machine with an NVIDIA driver needs to run
# the GPU benchmark (run_gpu.sh: brute force, frustum, CHC and the three-process cluster on the one
# GPU), with no network and no package installs there:
#   bin/        render_client, switch_node, frame_diff (wrappers: the right loader and libraries)
#   libexec/    the binaries themselves (stripped of debug info)
#   lib/        every shared library ldd lists except glibc's and libglvnd's (libstdc++, libgcc_s,
#               OpenSSL's libcrypto, tinygltf, stb, meshoptimizer, ...)
#   lib/glvnd/  libglvnd's libEGL.so.1 and libGLdispatch.so.0, used when the machine has no libEGL.so.1
#   lib/glibc/  this machine's glibc (loader, libc, libm, libpthread, ...), used when the machine's glibc
#               is older
#   scripts/    cluster.sh and lib.sh (the cluster launcher), VERSION, BUILD_INFO
#   scenes/     the shared real scenes (../shared/scenes, or $OCC_SHARED_DIR/scenes), if present
#   run_gpu.sh  the benchmark (run_gpu.sh --help)
# Not included: the GPU driver (libEGL_nvidia and its vendor file come with it; run_gpu.sh writes
# a vendor file when the driver's library is there but its file is not) and Mesa (llvmpipe: the
# machine's own Mesa is used with run_gpu.sh --allow-software). The folder must stay under 60 MB
# (checked).
#
#   scripts/gpu_bundle.sh DIR        (DIR must not exist or be empty; OCC_BIN: the binaries' folder)
#
# Then copy DIR to the GPU machine and run DIR/run_gpu.sh there.
set -euo pipefail
source "$(dirname "$0")/lib.sh"
dir=""
while [ $# -gt 0 ]; do
  case "$1" in
    -h|--help) occ_usage; exit 0 ;;
    -*) occ_unexpected "$1" ;;
    *) [ -z "$dir" ] || occ_unexpected "$1"; dir=$1; shift ;;
  esac
done
[ -n "$dir" ] || occ_die "the bundle folder is required: $OCC_SCRIPT DIR"
bins=(render_client switch_node frame_diff)
occ_require_bins "${bins[@]}"
if [ -e "$dir" ] && [ -n "$(ls -A "$dir")" ]; then occ_die "'$dir' exists and is not empty"; fi
for tool in ldd strip; do command -v $tool >/dev/null || occ_die "$tool not found (binutils / libc-bin)"; done
mkdir -p "$dir"/{bin,libexec,lib/glvnd,lib/glibc,scripts}
dir=$(cd "$dir" && pwd)

# glibc's own libraries (lib/glibc) and libglvnd's dispatch libraries (lib/glvnd).
glibc_re='^(ld-linux-x86-64\.so\.2|libc\.so\.6|libm\.so\.6|libpthread\.so\.0|libdl\.so\.2|librt\.so\.1|libresolv\.so\.2|libutil\.so\.1|libmvec\.so\.1)$'
glvnd_re='^(libEGL\.so\.1|libGLdispatch\.so\.0|libOpenGL\.so\.0)$'
for b in "${bins[@]}"; do
  strip --strip-debug -o "$dir/libexec/$b" "$BIN/$b"
  ldd "$BIN/$b" | awk '$2 == "=>" && $3 ~ /^\// { print $1, $3 } $1 ~ /^\/.*ld-linux/ { print "ld-linux-x86-64.so.2", $1 }'
done | sort -u | while read -r name path; do
  if [[ $name =~ $glibc_re ]]; then dest=lib/glibc
  elif [[ $name =~ $glvnd_re ]]; then dest=lib/glvnd
  else dest=lib
  fi
  cp -L "$path" "$dir/$dest/$name"
done
[ -e "$dir/lib/glibc/ld-linux-x86-64.so.2" ] || occ_die "ldd named no ld-linux-x86-64.so.2 (not an x86-64 build?)"
# glibc's other libraries too: the GPU driver's libraries link them (libpthread, libdl, librt), and
# with the bundle's loader they must come from the same glibc.
libc_dir=$(dirname "$(ldd "$BIN/render_client" | awk '$1 == "libc.so.6" { print $3 }')")
for name in libpthread.so.0 libdl.so.2 librt.so.1 libutil.so.1 libresolv.so.2 libmvec.so.1 libanl.so.1; do
  [ ! -e "$libc_dir/$name" ] || [ -e "$dir/lib/glibc/$name" ] || cp -L "$libc_dir/$name" "$dir/lib/glibc/$name"
done

# The wrappers: the machine's loader and glibc when they are new enough (run_gpu.sh decides and
# sets OCC_BUNDLE_GLIBC=1 otherwise), the bundle's libraries first either way.
for b in "${bins[@]}"; do
  cat >"$dir/bin/$b" <<EOF
#!/bin/sh
# $b from the occswitch GPU bundle (made by scripts/gpu_bundle.sh).
root=\$(cd "\$(dirname "\$0")/.." && pwd)
libs=\$root/lib\${OCC_BUNDLE_GLVND:+:\$root/lib/glvnd}
if [ -n "\${OCC_BUNDLE_GLIBC:-}" ]; then
  # The process would execute /proc/self/exe (the loader here) again to add this tunable
  # (common/memory.hpp, use_huge_pages): given now, it goes on at once.
  case "\${GLIBC_TUNABLES:-}" in
    *glibc.malloc.hugetlb*) ;;
    *) [ "\${OCC_HUGE_PAGES:-1}" = 0 ] || export GLIBC_TUNABLES=\${GLIBC_TUNABLES:+\$GLIBC_TUNABLES:}glibc.malloc.hugetlb=1 ;;
  esac
  exec "\$root/lib/glibc/ld-linux-x86-64.so.2" --library-path "\$root/lib/glibc:\$libs\${LD_LIBRARY_PATH:+:\$LD_LIBRARY_PATH}" "\$root/libexec/$b" "\$@"
fi
export LD_LIBRARY_PATH=\$libs\${LD_LIBRARY_PATH:+:\$LD_LIBRARY_PATH}
exec "\$root/libexec/$b" "\$@"
EOF
  chmod +x "$dir/bin/$b"
done

cp "$here/scripts/cluster.sh" "$here/scripts/lib.sh" "$dir/scripts/"
cp "$here/scripts/run_gpu.sh" "$dir/run_gpu.sh"
cp "$here/VERSION" "$dir/VERSION"
glibc=$(getconf GNU_LIBC_VERSION | awk '{ print $2 }')
{
  echo "occswitch $(cat "$here/VERSION") commit $(git -C "$here" rev-parse --short HEAD 2>/dev/null || echo unknown)"
  echo "made $(date -u +%Y-%m-%dT%H:%M:%SZ) on $(uname -m), glibc $glibc"
} >"$dir/BUILD_INFO"
echo "$glibc" >"$dir/lib/glibc/VERSION"

# The shared scenes: each folder that holds a glTF/GLB file, with its glTF, GLB, .bin and image
# files only (nothing else a folder may have gathered), while the bundle stays under its limit: the
# scenes run_gpu.sh names in its help first, then the smaller before the larger. A scene left out
# is named; copy it to the GPU machine by hand and give run_gpu.sh --scenes its path.
shared_scenes=${OCC_SHARED_DIR:-$here/../shared}/scenes
limit_kb=$((60 * 1024))
if [ -d "$shared_scenes" ]; then
  scene_files() { find "$shared_scenes/$1" -maxdepth 1 -type f \( -iname '*.gltf' -o -iname '*.glb' -o -iname '*.bin' \
    -o -iname '*.png' -o -iname '*.jpg' -o -iname '*.jpeg' -o -iname '*.ktx2' -o -iname '*.webp' \) -print0; }
  folders=$(cd "$shared_scenes" && find -L . -type f \( -iname '*.gltf' -o -iname '*.glb' \) -printf '%h\n' | sed 's|^\./||' | sort -u |
    while read -r f; do
      kb=$(scene_files "$f" | du -ckL --files0-from=- | tail -n 1 | awk '{ print $1 }')
      case "$f" in ReciprocatingSaw|bim/schependomlaan) rank=0 ;; *) rank=1 ;; esac
      echo "$rank $kb $f"
    done | sort -k1,1n -k2,2n)
  left_out=()
  while read -r rank kb f; do
    [ -n "$f" ] || continue
    used_kb=$(du -sk "$dir" | awk '{ print $1 }')
    # 1 MB kept free for du's rounding and the files still to come.
    if [ $((used_kb + kb + 1024)) -ge $limit_kb ]; then left_out+=("$f ($((kb / 1024)) MB)"); continue; fi
    mkdir -p "$dir/scenes/$f"
    scene_files "$f" | xargs -0 -r cp -L -t "$dir/scenes/$f"
  done <<<"$folders"
  if [ -d "$dir/scenes" ]; then
    [ ! -f "$shared_scenes/README.md" ] || cp "$shared_scenes/README.md" "$dir/scenes/"
    chmod -R u+w "$dir/scenes"
  fi
  [ ${#left_out[@]} = 0 ] ||
    echo "gpu_bundle: left out to stay under 60 MB: ${left_out[*]} (copy a scene's folder by hand and pass its path to run_gpu.sh --scenes)" >&2
else
  echo "gpu_bundle: no shared scenes at $shared_scenes: the bundle has the generated scenes only" >&2
fi

size_mb=$(du -sm "$dir" | awk '{ print $1 }')
[ "$size_mb" -lt 60 ] || occ_die "the bundle is $size_mb MB, over the 60 MB limit"
echo "gpu_bundle: $dir ($size_mb MB): $(cd "$dir" && find . -type f | wc -l) files; run $dir/run_gpu.sh on the GPU machine"
