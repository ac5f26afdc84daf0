#!/usr/bin/env python3
"""netlab.sh's repeated points (scripts/netlab_aggregate.py) on a hand-made runs file: medians of
odd and even counts, min and max, failed runs left out of the figures but counted, the frames each
figure rests on, points in the order they first ran; the plot script draws the result (when
gnuplot is there); netlab.sh rejects a bad --repeats with one line naming the flag.

usage: netlab_aggregate_test.py SOURCE_DIR
"""
import csv
import os
import shutil
import subprocess
import sys
import tempfile

src = sys.argv[1]
sys.path.insert(0, os.path.join(src, "scripts"))
import netlab_aggregate as agg  # noqa: E402

RUNS = """repeat,delay_ms,rate_mbit,chunk_ids,fps,latency_ms_mean,latency_ms_p95,bytes_per_frame,frames
1,5,10,100,35,80,90,1600,120
1,5,1000,100,48,70,85,1600,118
1,0,10,100,,,,,0
1,5,1000,10,47,60,70,1700,120
2,5,10,100,48,75,95,1620,119
2,5,1000,100,40,72,80,1580,120
2,0,10,100,,,,,0
3,5,10,100,40,77.5,91,1610,120
3,5,1000,100,44.5,71,82,1600,117
3,0,10,100,60.25,50,55,1500,120
"""

failures = []


def check(what, got, want):
    if got != want:
        failures.append(f"{what}: got {got!r}, want {want!r}")


check("median of 3", agg.median([48, 35, 40]), 40)
check("median of 2", agg.median([48, 40]), 44)
check("median of 1", agg.median([7.5]), 7.5)
check("number: integer", agg.number(44.0), "44")
check("number: decimals", agg.number(1.0 / 3), "0.3333")
check("number: trailing zeros", agg.number(77.5), "77.5")

tmp = tempfile.mkdtemp(prefix="netlab_agg_")
try:
    runs, out = os.path.join(tmp, "net_runs.csv"), os.path.join(tmp, "net.csv")
    with open(runs, "w") as f:
        f.write(RUNS)
    agg.main(["netlab_aggregate.py", runs, out])
    with open(out, newline="") as f:
        rows = list(csv.DictReader(f))
    check("header", list(rows[0].keys()), agg.HEADER)
    check("points in first-run order", [(r["delay_ms"], r["rate_mbit"], r["chunk_ids"]) for r in rows],
          [("5", "10", "100"), ("5", "1000", "100"), ("0", "10", "100"), ("5", "1000", "10")])
    a, b, c, _ = rows
    check("a runs", (a["runs"], a["failed"], a["frames"], a["frames_min"]), ("3", "0", "359", "119"))
    check("a fps", (a["fps"], a["fps_min"], a["fps_max"]), ("40", "35", "48"))
    check("a latency", (a["latency_ms_mean"], a["latency_ms_mean_min"], a["latency_ms_mean_max"]), ("77.5", "75", "80"))
    check("a p95", (a["latency_ms_p95"], a["latency_ms_p95_min"], a["latency_ms_p95_max"]), ("91", "90", "95"))
    check("a bytes", (a["bytes_per_frame"], a["bytes_per_frame_min"], a["bytes_per_frame_max"]), ("1610", "1600", "1620"))
    check("b fps", (b["fps"], b["fps_min"], b["fps_max"]), ("44.5", "40", "48"))
    check("b frames", (b["frames"], b["frames_min"]), ("355", "117"))
    check("c: one run of three", (c["runs"], c["failed"], c["frames"], c["fps"], c["fps_min"]), ("1", "2", "120", "60.25", "60.25"))
    # A point whose every run failed: runs 0, no figures.
    with open(runs, "w") as f:
        f.write(RUNS.splitlines()[0] + "\n1,20,10,100,,,,,0\n2,20,10,100,,,,,0\n")
    agg.main(["netlab_aggregate.py", runs, out])
    with open(out, newline="") as f:
        (d,) = list(csv.DictReader(f))
    check("all failed", (d["runs"], d["failed"], d["frames"], d["frames_min"], d["fps"]), ("0", "2", "0", "", ""))

    # The plots of the first file (medians with min-max bars) come out.
    if shutil.which("gnuplot"):
        with open(runs, "w") as f:
            f.write(RUNS)
        agg.main(["netlab_aggregate.py", runs, out])
        p = subprocess.run(["gnuplot", "-e", f"csv='{out}'; out='{tmp}'; rates='10 1000'",
                            os.path.join(src, "scripts", "netlab_plots.gp")], capture_output=True, text=True)
        check("gnuplot exit", (p.returncode, p.stderr), (0, ""))
        for png in ("net_fps.png", "net_latency.png"):
            check(png, os.path.isfile(os.path.join(tmp, png)) and os.path.getsize(os.path.join(tmp, png)) > 1000, True)

    for bad in ("0", "x", "-2"):
        p = subprocess.run(["bash", os.path.join(src, "scripts", "netlab.sh"), "--scene", "city", "--repeats", bad,
                            "--out", os.path.join(tmp, "never")], capture_output=True, text=True)
        check(f"--repeats {bad}", (p.returncode, p.stderr.strip()),
              (2, f"error: --repeats '{bad}': expected a whole number >= 1"))
finally:
    shutil.rmtree(tmp)

for f in failures:
    print("FAIL", f)
print(f"{len(failures)} failures")
sys.exit(1 if failures else 0)
