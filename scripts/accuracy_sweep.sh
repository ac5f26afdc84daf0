#!/usr/bin/env bash
# What accuracy costs in time: runs the cluster for tau in {0, 0.5, 1, 2, 5, 10, 20} px (visible-
# pixel LOD off and on, and front tracking off at one tau for comparison) and the full-detail
# reference renderer on the same path, then writes
#   OUT/accuracy.csv  tau, settings, mean/median frame ms, triangles drawn, |V|, bytes/frame,
#                     HC queries/frame, image error against the reference (differing-pixel
#                     fraction at threshold 0 and 16, PSNR), and the tau promise from item
#                     buffers (frame_diff --items): objects missing, the largest displacement (px),
#                     the share of pixels displaced beyond tau, and the same two without slivers
#                     at most two pixels thick (render_client/tools/item_diff.hpp)
#   OUT/accuracy.png  frame time against image error, one point per tau; below it the largest
#                     displacement against tau with the promise tau + 1, and the objects missing
#                     (gnuplot)
#
#   scripts/accuracy_sweep.sh --scene S --path P [--frames N] [--width W] [--height H] [--out DIR]
#                             [--taus "0 1 2"] [extra cluster args]
#
# Each configuration runs twice: once without images (the frame times) and once with images
# (the error), so PNG writing does not count as frame time. The LOD cache goes to OUT/lod-cache.
set -uo pipefail
source "$(dirname "$0")/lib.sh"
scene="" path="walk" frames=150 width=$OCC_WIDTH height=$OCC_HEIGHT out="out/accuracy"
taus="0 0.5 1 2 5 10 20"
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    --scene|--path|--frames|--width|--height|--out|--taus) occ_set "$@"; shift 2 ;;
    -h|--help) occ_usage; exit 0 ;;
    --*) occ_need_value "$@"; extra+=("$1" "$2"); shift 2 ;;
    *) occ_unexpected "$1" ;;
  esac
done
[ -n "$scene" ] || occ_die "--scene is required"
path=$(occ_frames_path "$path" "$frames")
command -v gnuplot >/dev/null || occ_die "gnuplot not installed (run scripts/setup.sh)"
occ_require_bins switch_node render_client frame_diff
mkdir -p "$out"
out=$(cd "$out" && pwd)
export LP_NUM_THREADS=${LP_NUM_THREADS:-1}
view=(--width "$width" --height "$height")
common=("${view[@]}" --lod-cache "$out/lod-cache" "${extra[@]}")
t_start=$SECONDS

echo "accuracy: reference (full detail) on $scene, $path, ${width}x${height}" >&2
"$BIN/render_client" --scene "$scene" --path "$path" --out "$out/reference" "${view[@]}" --images png+items \
  >"$out/reference.log" 2>&1 || { echo "error: reference failed (see $out/reference.log)" >&2; exit 1; }

# mean and median of a stats.csv column (skipping frame 0 and 1: no occluders yet)
col() {  # file column -> "mean median"
  awk -F, -v c="$2" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == c) k = i; next } NR > 3 && k { print $k }' "$1" |
    sort -g | awk '{ v[n++] = $1; s += $1 }
      END { if (!n) { print "nan nan"; exit } m = (n % 2) ? v[(n - 1) / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
            printf "%.3f %.3f\n", s / n, m }'
}

csv="$out/accuracy.csv"
echo "tau,visible_pixel_lod,front_tracking,frames,mean_frame_ms,median_frame_ms,triangles,visible,bytes_per_frame,queries,hc_ms,diff_fraction,diff_fraction_t16,psnr_db,objects_missing,max_displacement,beyond_tau_fraction,objects_missing_thick,max_thick_displacement" >"$csv"
configs=()
for t in $taus; do
  configs+=("$t off on")
  [ "$t" != "0" ] && configs+=("$t on on")
done
configs+=("0 off off" "2 off off")
for cfg in "${configs[@]}"; do
  read -r tau vp ft <<<"$cfg"
  name="tau${tau}_vp${vp}_ft${ft}"
  args=(--pixel-error "$tau" --visible-pixel-lod "$vp" --front-tracking "$ft" "${common[@]}")
  echo "accuracy: $name ($((SECONDS - t_start)) s)" >&2
  "$here/scripts/cluster.sh" --scene "$scene" --path "$path" --out "$out/$name-time" --images off "${args[@]}" \
    >"$out/$name-time.out" 2>&1 || { echo "error: cluster run $name failed (see $out/$name-time/)" >&2; exit 1; }
  "$here/scripts/cluster.sh" --scene "$scene" --path "$path" --out "$out/$name" --images png+items "${args[@]}" \
    >"$out/$name.out" 2>&1 || { echo "error: cluster run $name failed (see $out/$name/)" >&2; exit 1; }
  s="$out/$name-time/stats.csv"
  read -r fmean fmed <<<"$(col "$s" frame_interval_ms)"
  read -r tri _ <<<"$(col "$s" triangles)"
  read -r vis _ <<<"$(col "$s" visible)"
  read -r bytes _ <<<"$(col "$s" bytes_received)"
  read -r q _ <<<"$(col "$s" queries)"
  read -r hc _ <<<"$(col "$s" hc_ms)"
  nf=$(($(wc -l <"$s") - 1))
  d0=$("$BIN/frame_diff" "$out/reference" "$out/$name" --psnr | tail -n 1)
  d16=$("$BIN/frame_diff" "$out/reference" "$out/$name" --threshold 16 --psnr | tail -n 1)
  frac=$(sed -n 's/.*mean_fraction=\([^ ]*\).*/\1/p' <<<"$d0")
  frac16=$(sed -n 's/.*mean_fraction=\([^ ]*\).*/\1/p' <<<"$d16")
  psnr=$(sed -n 's/.*psnr_db=\([^ ]*\).*/\1/p' <<<"$d0")
  di=$("$BIN/frame_diff" "$out/reference" "$out/$name" --items --tau "$tau" | tee "$out/$name-items.txt" | tail -n 1)
  item_cols=""
  for k in objects_missing max_displacement beyond_tau_fraction objects_missing_thick max_thick_displacement; do
    item_cols+=",$(sed -n "s/.* $k=\([^ ]*\).*/\1/p;s/^$k=\([^ ]*\).*/\1/p" <<<"$di" | head -n 1)"
  done
  echo "$tau,$vp,$ft,$nf,$fmean,$fmed,$tri,$vis,$bytes,$q,$hc,$frac,$frac16,$psnr$item_cols" >>"$csv"
  rm -f "$out/$name"/frame_*.png "$out/$name"/items_*.png "$out/$name"/depth_*.png  # keep the logs and stats
done
read -r refmean refmed <<<"$(col "$out/reference/stats.csv" render_ms)"

gnuplot <<EOF
set terminal pngcairo size 900,1000 font ",10"
set output "$out/accuracy.png"
set datafile separator ","
set multiplot layout 2,1
set title "$(basename "$scene"), $path, ${width}x${height}: frame time vs image error (labels: tau px)" noenhanced
set xlabel "pixels differing from the full-detail reference (%, mean over frames)"
set ylabel "frame time (ms, mean)"
set grid
set key top right
set offsets graph 0.05, graph 0.1, graph 0.1, graph 0.1
plot "$csv" using (strcol(2) eq "off" && strcol(3) eq "on" ? 100*\$12 : 1/0):5 with linespoints pt 7 title "visible-pixel LOD off", \
     "$csv" using (strcol(2) eq "off" && strcol(3) eq "on" ? 100*\$12 : 1/0):5:(sprintf("%g", \$1)) with labels offset 0,1 notitle, \
     "$csv" using (strcol(2) eq "on" ? 100*\$12 : 1/0):5 with linespoints pt 5 title "visible-pixel LOD on", \
     "$csv" using (strcol(2) eq "on" ? 100*\$12 : 1/0):5:(sprintf("%g", \$1)) with labels offset 0,-1 notitle, \
     "$csv" using (strcol(3) eq "off" ? 100*\$12 : 1/0):5 with points pt 9 ps 1.5 title "front tracking off"
set title "the tau promise (frame_diff --items): largest displacement against tau; labels: objects missing (thicker than slivers)" noenhanced
set xlabel "tau (px)"
set ylabel "largest displacement (px, over all frames)"
set key top left
set yrange [0:*]
set offsets graph 0.05, graph 0.05, graph 0.1, 0
plot x + 1 with lines dt 2 lc rgb "gray40" title "promise: tau + 1", \
     "$csv" using (strcol(3) eq "on" ? \$1 : 1/0):(\$16 > 1e9 ? 1/0 : \$16) with points pt 7 title "all pixels", \
     "$csv" using (strcol(3) eq "on" ? \$1 : 1/0):19 with points pt 6 ps 1.5 title "without slivers (<= 2 px thick)", \
     "$csv" using (strcol(3) eq "on" ? \$1 : 1/0):19:(sprintf("%d (%d)", \$15, \$18)) with labels offset 0,1 notitle
unset multiplot
EOF
echo "accuracy: done in $((SECONDS - t_start)) s: $csv, $out/accuracy.png (reference: mean render ${refmean} ms/frame)" >&2
column -s, -t "$csv"
