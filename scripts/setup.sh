#!/usr/bin/env bash
# Installs everything occswitch needs from Debian packages. Idempotent: only missing
# packages are installed, so a second run costs one dpkg query.
set -euo pipefail
source "$(dirname "$0")/lib.sh"  # --version
occ_help_first "$@"  # before anything is installed or built

PKGS=(
  build-essential cmake pkg-config
  libegl-dev libegl-mesa0 libgl1-mesa-dri libosmesa6-dev libgl-dev   # headless GL: EGL + OSMesa (Mesa llvmpipe)
  libglm-dev                                               # vector math
  libboost-dev libboost-system-dev                         # Boost.Asio transport
  libssl-dev                                               # cluster key: HMAC-SHA256 (OpenSSL libcrypto)
  libtinygltf-dev nlohmann-json3-dev libstb-dev            # glTF 2.0 loading (+ PNG via stb)
  libassimp-dev libtinyobjloader-dev                       # STL, FBX, COLLADA, ...; OBJ (PLY: our reader)
  libmeshoptimizer-dev                                     # simplifier for LOD/HLOD
  libgtest-dev libgmock-dev                                # tests
  gnuplot-nox                                              # plots in benchmarks
  iproute2 python3                                         # netlab / scripts
  libx11-dev                                               # render_client --window (Xlib)
  xvfb xdotool                                             # window tests (virtual X server, key presses)
  ffmpeg                                                   # scripts/video.sh (frames -> MP4)
  openmpi-bin                                              # mpirun: scripts/cluster_rank.sh under a job launcher (tests)
  openssh-server                                           # sshd in network namespaces: cluster.sh --hosts tests
)

missing=()
for p in "${PKGS[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PKGS[@]} packages present"
  exit 0
fi

echo "setup: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "setup: done"
