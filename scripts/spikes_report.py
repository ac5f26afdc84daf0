#!/usr/bin/env python3
"""One line per cluster run (stats.csv of scripts/cluster.sh): frame-interval median / mean / p99
and their ratios, ids sent per frame (added + removed) against |V|, bytes per frame, the most
leaves in one frame, and PVS/exact when an item-buffer run is given.

  scripts/spikes_report.py RUN_DIR [--full-sets DIR] [--exact DIR [--exact-every K]] [--label L]

Frame 0 is left out of every figure (start-up, and its set is sent whole). --exact DIR: a
`render_client --reference --cull frustum --exact` run on every K-th camera of the same path
(frame j there = frame j*K here); PVS/exact = mean over those frames of |V| / exact (a frame that
sees nothing and draws nothing counts 1)."""
import argparse, csv, math, statistics


def rows(d):
    with open(f"{d}/stats.csv") as f:
        return [{k: float(v) for k, v in r.items() if v not in ("", None)} for r in csv.DictReader(f)]


def p(sorted_v, q):
    return sorted_v[max(0, math.ceil(q * len(sorted_v)) - 1)]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run")
    ap.add_argument("--full-sets")
    ap.add_argument("--exact")
    ap.add_argument("--exact-every", type=int, default=1)
    ap.add_argument("--label", default="")
    a = ap.parse_args()
    r = rows(a.run)[1:]
    iv = sorted(x["frame_interval_ms"] for x in r)
    med, mean, p99 = statistics.median(iv), statistics.mean(iv), p(iv, 0.99)
    ids = sum(x["added"] + x["removed"] for x in r)
    vis = sum(x["visible"] for x in r)
    out = [a.label or a.run, f"median {med:.1f}", f"mean {mean:.1f}", f"p99 {p99:.1f} ms",
           f"p99/med {p99 / med:.2f}", f"mean/med {mean / med:.2f}",
           f"|V| {vis / len(r):.1f}", f"ids/frame {ids / len(r):.1f}", f"saved {100 * (1 - ids / max(vis, 1)):.1f}%",
           f"B/frame {statistics.mean(x['bytes_received'] for x in r):.0f}",
           f"max |V| {max(x['visible'] for x in r):.0f}"]
    if a.full_sets:
        fr = rows(a.full_sets)[1:]
        out.append(f"full-sets B/frame {statistics.mean(x['bytes_received'] for x in fr):.0f}")
    if a.exact:
        ex = rows(a.exact)
        allr = rows(a.run)
        ratios = []
        for j, e in enumerate(ex):
            f = j * a.exact_every
            if f == 0 or f >= len(allr):
                continue
            v, x = allr[f]["visible"], e["exact_visible"]
            ratios.append(1.0 if v == 0 and x == 0 else v / max(x, 1))
        out.append(f"PVS/exact {statistics.mean(ratios):.2f} (max {max(ratios):.1f}, {len(ratios)} frames)")
    print(" | ".join(out))


if __name__ == "__main__":
    main()
