# gnuplot -e "csv='net.csv'; out='DIR'; rates='10 100 1000'" scripts/netlab_plots.gp
# net.csv (scripts/netlab_aggregate.py) columns: 1 delay_ms, 2 rate_mbit, 3 chunk_ids, 4 runs,
# 5 failed, 6 frames, 7 frames_min, then median,min,max of: 8-10 fps, 11-13 latency_ms_mean,
# 14-16 latency_ms_p95, 17-19 bytes_per_frame. Each point is drawn at its median with a bar from
# the smallest to the largest run (yerrorlines: x:y:ylow:yhigh).
# Rows of one series are picked and sorted with awk so gnuplot draws each series as one line; a
# point without a completed run (runs 0) is left out.
set terminal pngcairo size 900,500 font ",10"
set datafile separator ","
set key outside right
set grid
set offsets graph 0.03, graph 0.03, 0, 0  # room for the bars of the first and last point
rate_rows(r) = sprintf("< awk -F, 'NR > 1 && $4 > 0 && $3 == 100 && $2 == %s' '%s' | sort -t, -k1,1n -u", r, csv)
set xlabel "one-way delay per link (ms)"
set output out."/net_fps.png"
set title "Frame rate against link delay (diff chunk b = 100; median of the runs, bars min-max)"
set ylabel "fps"
plot for [r in rates] rate_rows(r) using 1:8:9:10 with yerrorlines lw 1.5 title r." Mbit/s"
set output out."/net_latency.png"
set title "Camera-to-display latency against link delay (b = 100; median, bars min-max)"
set ylabel "latency ms (mean solid; p95 dashed)"
plot for [r in rates] rate_rows(r) using 1:11:12:13 with yerrorlines lw 1.5 title r." Mbit/s mean", \
     for [r in rates] rate_rows(r) using 1:14:15:16 with yerrorlines dt 2 title r." Mbit/s p95"
