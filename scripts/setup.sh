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
  assimp-utils                                             # tests: `assimp export` writes their FBX files
  libmeshoptimizer-dev                                     # simplifier for LOD/HLOD
  libgtest-dev libgmock-dev                                # tests
  gnuplot-nox                                              # plots in benchmarks
  iproute2 python3                                         # netlab / scripts
  libx11-dev                                               # render_client --window (Xlib)
  libturbojpeg0-dev zlib1g-dev                             # render_client --web: JPEG frames, PNG stills
  chromium nodejs                                          # the --web browser test (headless; puppeteer-core below)
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

# npm comes with Debian's nodejs from package npm, inside nodejs elsewhere (NodeSource).
command -v npm >/dev/null || dpkg-query -W -f='${Status}' npm 2>/dev/null | grep -q "install ok installed" ||
  missing+=(npm)

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PKGS[@]} packages present"
else
  echo "setup: installing ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# puppeteer-core for the browser test (tests/web/package.json pins it; package-lock.json the
# rest), into tests/web/node_modules (ignored by git). It drives /usr/bin/chromium: no browser
# download.
web="$(cd "$(dirname "$0")/.." && pwd)/tests/web"
want=$(sed -n 's/.*"puppeteer-core": "\(.*\)".*/\1/p' "$web/package.json")
have=$(sed -n 's/^  "version": "\(.*\)".*/\1/p' "$web/node_modules/puppeteer-core/package.json" 2>/dev/null || true)
if [ "$have" != "$want" ]; then
  echo "setup: npm ci puppeteer-core@$want into tests/web/node_modules"
  (cd "$web" && PUPPETEER_SKIP_DOWNLOAD=1 npm ci --no-audit --no-fund --omit=dev --silent)
fi
echo "setup: done"
