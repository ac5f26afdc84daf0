# gnuplot -e "before='B.dat'; after='A.dat'; out='docs/x.png'; name='...'" scripts/spikes_plot.gp
# Frame time along a walk before/after (dat files from scripts/spikes_report.py --dat): the measured
# frame interval, the three-machine model from CPU times, and the ids sent per frame.
set terminal pngcairo size 1100,900 font ",10"
set output out
set datafile commentschars "#"
set multiplot layout 3,1 title name
set grid
set key top right
set xlabel "frame"
set ylabel "frame interval, ms (wall clock)"
set logscale y
plot before using 1:2 with lines lw 1 lc rgb "#d04020" title "before", \
     after using 1:2 with lines lw 1 lc rgb "#2060c0" title "after"
set ylabel "model ms (CPU times, one machine per process)"
plot before using 1:3 with lines lw 1 lc rgb "#d04020" title "before", \
     after using 1:3 with lines lw 1 lc rgb "#2060c0" title "after"
unset logscale y
set ylabel "ids sent (added + removed)"
plot before using 1:5 with lines lw 1 lc rgb "#d04020" title "before", \
     after using 1:5 with lines lw 1 lc rgb "#2060c0" title "after"
unset multiplot
