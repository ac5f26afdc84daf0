# gnuplot -e "out='DIR'" scripts/bench_plots.gp : plots of a scripts/bench.sh run.
set terminal pngcairo size 1000,500 font ",10"
set datafile commentschars "#"
set key outside right
set grid
set output out."/fps_along_path.png"
set title "Frame rate along the path"
set xlabel "frame"
set ylabel "fps"
set logscale y
plot for [i=2:7] out."/per_frame.dat" using 1:i with lines lw 1.5 \
  title word("none frustum stop-and-wait chc gigawalk switch", i-1)
unset logscale y
set output out."/nodes_sent.png"
set title "Node ids sent per frame, with and without incremental transmission"
set ylabel "ids per frame"
plot out."/per_frame.dat" using 1:9 with lines lw 1.5 title "full sets", \
     out."/per_frame.dat" using 1:8 with lines lw 1.5 title "incremental"
