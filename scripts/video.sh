#!/usr/bin/env bash
# Turns a run's frames (DIR/frame_NNNNN.png, from render_client --out or scripts/cluster.sh) into
# an H.264 MP4 that any player or browser shows: DIR/video.mp4 (or --out FILE).
#
#   scripts/video.sh DIR [--fps N] [--out FILE.mp4]
#
# --fps: frames per second of the video (default 30). Needs ffmpeg (scripts/setup.sh installs it).
set -euo pipefail
dir="" fps=30 out=""
while [ $# -gt 0 ]; do
  case "$1" in
    --fps) [ $# -ge 2 ] || { echo "error: --fps needs a value" >&2; exit 2; }; fps=$2; shift 2 ;;
    --out) [ $# -ge 2 ] || { echo "error: --out needs a value" >&2; exit 2; }; out=$2; shift 2 ;;
    -h|--help) sed -n '2,7p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    --version) echo "video.sh (occswitch) $(cat "$(dirname "$0")/../VERSION" 2>/dev/null || echo unknown)"; exit 0 ;;
    --*) echo "error: unknown flag $1 (see scripts/video.sh --help)" >&2; exit 2 ;;
    *) [ -z "$dir" ] || { echo "error: one folder only, got '$dir' and '$1'" >&2; exit 2; }; dir=$1; shift ;;
  esac
done
[ -n "$dir" ] || { echo "error: give the folder with the frames (see scripts/video.sh --help)" >&2; exit 2; }
[ -d "$dir" ] || { echo "error: '$dir': not a folder" >&2; exit 2; }
[[ "$fps" =~ ^[0-9]+$ && "$fps" -ge 1 && "$fps" -le 240 ]] || { echo "error: --fps '$fps': must be 1..240" >&2; exit 2; }
command -v ffmpeg >/dev/null || { echo "error: ffmpeg not found (scripts/setup.sh installs it)" >&2; exit 2; }
n=$(find "$dir" -maxdepth 1 -name 'frame_[0-9][0-9][0-9][0-9][0-9].png' | wc -l)
[ "$n" -gt 0 ] || { echo "error: '$dir' has no frame_NNNNN.png (render with --out and without --images off)" >&2; exit 2; }
first=$(find "$dir" -maxdepth 1 -name 'frame_[0-9][0-9][0-9][0-9][0-9].png' | sort | head -1)
start=$(basename "$first" .png); start=$((10#${start#frame_}))
out=${out:-$dir/video.mp4}
# Even width and height (H.264 4:2:0 needs them), yuv420p for players, faststart for the web.
ffmpeg -hide_banner -loglevel error -y -framerate "$fps" -start_number "$start" -i "$dir/frame_%05d.png" \
  -vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2' -c:v libx264 -pix_fmt yuv420p -movflags +faststart "$out"
echo "video: $n frames at $fps fps -> $out"
