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
set xlabel "frame (frames 0-1 left out: frame 0 draws everything, frame 1 removes most of it)"
plot out."/per_frame.dat" using ($1 > 1 ? $1 : 1/0):9 with lines lw 1.5 title "full sets", \
     out."/per_frame.dat" using ($1 > 1 ? $1 : 1/0):8 with lines lw 1.5 title "incremental"
