# gnuplot -e "dir='OUT'" scripts/scale_plot.gp   (OUT/scale_{frustum,chc,switch}.csv -> OUT/scale.png)
# Frame time and peak memory against scene size (scripts/scale_matrix.sh): one line per method.
set terminal pngcairo size 1100,500 font ",10"
set output dir."/scale.png"
set datafile separator ","
set multiplot layout 1,2 title "plant:M on llvmpipe (LP\\_NUM\\_THREADS=1), --images off"
set grid
set logscale xy
set key top left
set xlabel "scene size, million triangles"
set ylabel "frame time, ms (mean)"
plot dir."/scale_frustum.csv" using 1:3 with linespoints lw 2 pt 7 lc rgb "#d04020" title "frustum culling", \
     dir."/scale_chc.csv" using 1:3 with linespoints lw 2 pt 5 lc rgb "#20a040" title "CHC", \
     dir."/scale_switch.csv" using 1:3 with linespoints lw 2 pt 9 lc rgb "#2060c0" title "switch (3 processes)"
set ylabel "peak resident memory, MB (switch: sum of 3 processes)"
plot dir."/scale_frustum.csv" using 1:7 with linespoints lw 2 pt 7 lc rgb "#d04020" title "frustum culling", \
     dir."/scale_chc.csv" using 1:7 with linespoints lw 2 pt 5 lc rgb "#20a040" title "CHC", \
     dir."/scale_switch.csv" using 1:7 with linespoints lw 2 pt 9 lc rgb "#2060c0" title "switch (3 processes)"
unset multiplot
