# gnuplot -e "csv='net.csv'; out='DIR'; chunk_delay=5; rates='10 100 1000'" scripts/netlab_plots.gp
set terminal pngcairo size 900,500 font ",10"
set datafile separator ","
set key outside right
set grid
set xlabel "one-way delay per link (ms)"
set output out."/net_fps.png"
set title "Frame rate against link delay (diff chunk b = 100)"
set ylabel "fps"
plot for [r in rates] csv using ($3 == 100 && $2 == r + 0 ? $1 : 1/0):4 with linespoints lw 1.5 title r." Mbit/s"
set output out."/net_latency.png"
set title "Camera-to-display latency against link delay (b = 100)"
set ylabel "latency ms (mean; p95 dashed)"
plot for [r in rates] csv using ($3 == 100 && $2 == r + 0 ? $1 : 1/0):5 with linespoints lw 1.5 title r." Mbit/s mean", \
     for [r in rates] csv using ($3 == 100 && $2 == r + 0 ? $1 : 1/0):6 with linespoints dt 2 title r." Mbit/s p95"
set output out."/net_chunks.png"
set title sprintf("Diff chunk size b against latency (delay %g ms, 1000 Mbit/s)", chunk_delay)
set xlabel "node ids per diff message (b)"
set logscale x
set ylabel "ms / fps"
plot csv using ($1 == chunk_delay && $2 == 1000 ? $3 : 1/0):5 with linespoints lw 1.5 title "latency mean ms", \
     csv using ($1 == chunk_delay && $2 == 1000 ? $3 : 1/0):4 with linespoints lw 1.5 title "fps"
