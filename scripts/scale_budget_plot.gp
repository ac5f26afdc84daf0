# gnuplot -e "dir='OUT'" scripts/scale_budget_plot.gp   (OUT/budget_{auto,all}.csv -> OUT/budget.png)
# Memory and frame rate against scene size (scripts/scale_budget.sh): within the default
# geometry budget and with everything resident.
set terminal pngcairo size 1100,500 font ",10"
set output dir."/budget.png"
set datafile separator ","
set multiplot layout 1,2 title "plant:M, the switch (3 processes), 1024^2, tau 1, llvmpipe (LP\\_NUM\\_THREADS=1)"
set grid
set logscale x
set key top left
set xlabel "scene size, million triangles"
set ylabel "peak resident memory of the 3 processes, GB"
plot dir."/budget_auto.csv" using 1:($6/1024) with linespoints lw 2 pt 7 lc rgb "#2060c0" title "--geometry-budget auto", \
     dir."/budget_all.csv" using 1:($6/1024) with linespoints lw 2 pt 5 lc rgb "#d04020" title "--geometry-budget all"
set ylabel "frames per second (mean)"
set key top right
plot dir."/budget_auto.csv" using 1:3 with linespoints lw 2 pt 7 lc rgb "#2060c0" title "--geometry-budget auto", \
     dir."/budget_all.csv" using 1:3 with linespoints lw 2 pt 5 lc rgb "#d04020" title "--geometry-budget all"
unset multiplot
