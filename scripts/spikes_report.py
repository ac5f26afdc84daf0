#!/usr/bin/env python3
"""One line per cluster run (stats.csv of scripts/cluster.sh): frame-interval median / mean / p99
and their ratios, ids sent per frame (added + removed) against |V|, bytes per frame, the most
leaves in one frame, and PVS/exact when an item-buffer run is given.

  scripts/spikes_report.py RUN_DIR [--full-sets DIR] [--exact DIR [--exact-every K]] [--label L]

Frame 0 is left out of every figure (start-up, and its set is sent whole). --exact DIR: a
`render_client --reference --cull frustum --exact` run on every K-th camera of the same path
(frame j there = frame j*K here); PVS/exact = mean over those frames of |V| / exact (a frame that
sees nothing and draws nothing counts 1).

"model": the per-frame three-machine frame time of scripts/bench_report.py (one machine per
process, 0 ms links, 1 Gbit/s, lookahead 3) from the CPU times the processes measured: it depends
much less than the wall-clock interval on what else runs on this shared 2-core machine."""
import argparse, csv, math, statistics


def rows(d):
    with open(f"{d}/stats.csv") as f:
        return [{k: float(v) for k, v in r.items() if v not in ("", None)} for r in csv.DictReader(f)]


def p(sorted_v, q):
    return sorted_v[max(0, math.ceil(q * len(sorted_v)) - 1)]


def model_ms(r):
    """Per frame: max((HC + OR) / 2, RVG, (OR - OR tail) / 2, HC(f) + bytes + OR tail(f+1)), CPU times."""
    out = []
    for i, x in enumerate(r):
        terms = [(x["hc_cpu_ms"] + x["or_cpu_ms"]) / 2, x["rvg_frame_cpu_ms"], (x["or_cpu_ms"] - x["or_tail_cpu_ms"]) / 2]
        if i + 1 < len(r):
            terms.append(x["hc_cpu_ms"] + x["bytes_received"] * 8 / 1e9 * 1e3 + r[i + 1]["or_tail_cpu_ms"])
        out.append(max(terms))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run")
    ap.add_argument("--full-sets")
    ap.add_argument("--exact")
    ap.add_argument("--exact-every", type=int, default=1)
    ap.add_argument("--label", default="")
    ap.add_argument("--dat", help="write frame, interval ms, model ms, |V|, ids sent per line here")
    a = ap.parse_args()
    r = rows(a.run)[1:]
    iv = sorted(x["frame_interval_ms"] for x in r)
    med, mean, p99 = statistics.median(iv), statistics.mean(iv), p(iv, 0.99)
    mo = model_ms(r)
    ms = sorted(mo)
    mmed, mmean, mp99 = statistics.median(ms), statistics.mean(ms), p(ms, 0.99)
    if a.dat:
        with open(a.dat, "w") as f:
            f.write("# frame interval_ms model_ms visible ids_sent\n")
            for x, m in zip(r, mo):
                f.write(f"{x['frame']:.0f} {x['frame_interval_ms']:.3f} {m:.3f} {x['visible']:.0f} {x['added'] + x['removed']:.0f}\n")
    ids = sum(x["added"] + x["removed"] for x in r)
    vis = sum(x["visible"] for x in r)
    out = [a.label or a.run, f"median {med:.1f}", f"mean {mean:.1f}", f"p99 {p99:.1f} ms",
           f"p99/med {p99 / med:.2f}", f"mean/med {mean / med:.2f}",
           f"model {mmed:.1f}/{mmean:.1f}/{mp99:.1f} ms, p99/med {mp99 / mmed:.2f}, mean/med {mmean / mmed:.2f}",
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
