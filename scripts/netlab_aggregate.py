#!/usr/bin/env python3
"""netlab.sh's figures over repeated runs: reads OUT/net_runs.csv (one row per run of a point:
repeat,delay_ms,rate_mbit,chunk_ids,fps,latency_ms_mean,latency_ms_p95,bytes_per_frame,frames; a
failed run has empty figures and 0 frames) and writes OUT/net.csv, one row per delay x rate x chunk
point in the order the points first ran:

  delay_ms,rate_mbit,chunk_ids   the point
  runs,failed                    runs whose figures are taken, runs that failed
  frames,frames_min              frames completed in those runs together, and in the shortest one:
                                 what each figure rests on
  F,F_min,F_max                  for F = fps, latency_ms_mean, latency_ms_p95, bytes_per_frame: the
                                 median over the runs (of an even count: the mean of the middle
                                 two), the smallest and the largest

A point without a completed run gets runs 0 and empty figures.

usage: netlab_aggregate.py RUNS_CSV OUT_CSV
"""
import csv
import sys

POINT = ["delay_ms", "rate_mbit", "chunk_ids"]
FIGURES = ["fps", "latency_ms_mean", "latency_ms_p95", "bytes_per_frame"]
HEADER = POINT + ["runs", "failed", "frames", "frames_min"] + [
    f"{f}{s}" for f in FIGURES for s in ("", "_min", "_max")]


def median(values):
    v = sorted(values)
    n = len(v)
    return v[n // 2] if n % 2 else (v[n // 2 - 1] + v[n // 2]) / 2


def number(x):
    """As short as it is exact enough to read: integers without a point, else 4 significant decimals."""
    if x == int(x) and abs(x) < 1e15:
        return str(int(x))
    return f"{x:.4f}".rstrip("0").rstrip(".")


def completed(row):
    return all(row[f] != "" for f in FIGURES) and int(row["frames"] or 0) > 0


def aggregate(rows):
    points = {}  # point -> its runs, in first-run order (dicts keep insertion order)
    for row in rows:
        points.setdefault(tuple(row[k] for k in POINT), []).append(row)
    out = []
    for point, runs in points.items():
        done = [r for r in runs if completed(r)]
        line = list(point) + [str(len(done)), str(len(runs) - len(done))]
        if not done:
            out.append(line + ["0", ""] + [""] * (3 * len(FIGURES)))
            continue
        frames = [int(r["frames"]) for r in done]
        line += [str(sum(frames)), str(min(frames))]
        for f in FIGURES:
            v = [float(r[f]) for r in done]
            line += [number(median(v)), number(min(v)), number(max(v))]
        out.append(line)
    return out


def main(argv):
    if len(argv) != 3:
        sys.exit("usage: netlab_aggregate.py RUNS_CSV OUT_CSV")
    with open(argv[1], newline="") as f:
        rows = list(csv.DictReader(f))
    with open(argv[2], "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(HEADER)
        w.writerows(aggregate(rows))


if __name__ == "__main__":
    main(sys.argv)
