# gnuplot -e "csv='net.csv'; out='DIR'; chunk_delay=5; rates='10 100 1000'" scripts/netlab_plots.gp
# net.csv columns: delay_ms,rate_mbit,chunk_ids,fps,latency_ms_mean,latency_ms_p95,bytes_per_frame,frames
# Rows of one series are picked and sorted with awk so gnuplot draws each series as one line.
set terminal pngcairo size 900,500 font ",10"
set datafile separator ","
set key outside right
set grid
rate_rows(r) = sprintf("< awk -F, 'NR > 1 && $3 == 100 && $2 == %s' '%s' | sort -t, -k1,1n -u", r, csv)
chunk_rows = sprintf("< awk -F, 'NR > 1 && $1 == %g && $2 == 1000' '%s' | sort -t, -k3,3n -u", chunk_delay, csv)
set xlabel "one-way delay per link (ms)"
set output out."/net_fps.png"
set title "Frame rate against link delay (diff chunk b = 100)"
set ylabel "fps"
plot for [r in rates] rate_rows(r) using 1:4 with linespoints lw 1.5 title r." Mbit/s"
set output out."/net_latency.png"
set title "Camera-to-display latency against link delay (b = 100)"
set ylabel "latency ms (mean solid; p95 dashed)"
plot for [r in rates] rate_rows(r) using 1:5 with linespoints lw 1.5 title r." Mbit/s mean", \
     for [r in rates] rate_rows(r) using 1:6 with linespoints dt 2 title r." Mbit/s p95"
set output out."/net_chunks.png"
set title sprintf("Diff chunk size b against latency (delay %g ms, 1000 Mbit/s)", chunk_delay)
set xlabel "node ids per diff message (b)"
set logscale x
set ylabel "ms / fps"
plot chunk_rows using 3:5 with linespoints lw 1.5 title "latency mean ms", \
     chunk_rows using 3:6 with linespoints dt 2 title "latency p95 ms", \
     chunk_rows using 3:4 with linespoints lw 1.5 title "fps"
