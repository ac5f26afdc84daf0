#!/usr/bin/env python3
"""Frame-time spikes, id churn and PVS size of cluster runs (docs/spikes.md).

  scripts/spikes_report.py RUN_DIR [--exact DIR [--exact-every K]] [--label L] [--dat F]
  scripts/spikes_report.py --table BEFORE_DIR AFTER_DIR      (two scripts/spikes_matrix.sh outputs)

One line per run (stats.csv of scripts/cluster.sh): frame-interval median / mean / p99 and their
ratios, ids sent per frame (added + removed) against |V|, bytes per frame, the most leaves in one
frame, and PVS/exact when an item-buffer run is given. --table prints a markdown table, before ->
after, for every run the two matrices share.

Frame 0 is left out of every figure (start-up, and its set is sent whole). --exact DIR: a
`render_client --cull frustum --exact` run on every K-th camera of the same path
(frame j there = frame j*K here); PVS/exact = mean over those frames of |V| / exact (a frame that
sees nothing and draws nothing counts 1). With K = 1 (every camera) it also gives the exact set's
own ids saved: what an incremental set of exactly the visible leaves would save on this path;
and "oracle": median/p99 CPU ms of a render of exactly the visible nodes (the exact run's
oracle_cpu_ms), the scene's own variation from frame to frame.

"model": the per-frame three-machine frame time of scripts/bench_report.py (one machine per
process, 0 ms links, 1 Gbit/s, lookahead 3) from the CPU times the processes measured: it depends
much less than the wall-clock interval on what else runs on this shared 2-core machine."""
import argparse, math, os, statistics

from bench_report import read_rows  # beside this script


def rows(d):
    """d/stats.csv as numbers; text columns (the render client's `mode`) are left out."""
    return read_rows(f"{d}/stats.csv")


def pct(sorted_v, q):
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


def figures(run, exact=None, every=1):
    allr = rows(run)
    r = allr[1:]
    iv = sorted(x["frame_interval_ms"] for x in r)
    mo = sorted(model_ms(r))
    ids = sum(x["added"] + x["removed"] for x in r)
    vis = sum(x["visible"] for x in r)
    f = dict(med=statistics.median(iv), mean=statistics.mean(iv), p99=pct(iv, 0.99),
             mmed=statistics.median(mo), mmean=statistics.mean(mo), mp99=pct(mo, 0.99),
             V=vis / len(r), ids=ids / len(r), saved=100 * (1 - ids / max(vis, 1)),
             B=statistics.mean(x["bytes_received"] for x in r), maxV=max(x["visible"] for x in r))
    if r and "full_set_bytes" in r[0]:  # what the whole visible sets would have taken
        f["Bfull"] = statistics.mean(x["full_set_bytes"] for x in r)
    if exact and os.path.exists(f"{exact}/stats.csv"):
        ratios = []
        for j, e in enumerate(rows(exact)):
            k = j * every
            if k == 0 or k >= len(allr):
                continue
            v, x = allr[k]["visible"], e["exact_visible"]
            ratios.append(1.0 if v == 0 and x == 0 else v / max(x, 1))
        f["pvs"], f["pvsmax"] = statistics.mean(ratios), max(ratios)
        er = rows(exact)[1:]
        if every == 1 and er and "exact_added" in er[0]:
            # The exact set's own churn over the same frames: the most an incremental set of the
            # exactly visible leaves could save on this path.
            eids = sum(x["exact_added"] + x["exact_removed"] for x in er)
            f["exact_saved"] = 100 * (1 - eids / max(sum(x["exact_visible"] for x in er), 1))
        if er and "oracle_cpu_ms" in er[0]:
            # A render of exactly the visible nodes (CPU time): the scene's own frame-to-frame
            # variation, which no renderer that draws what is visible can go below.
            oc = sorted(x["oracle_cpu_ms"] for x in er)
            f["omed"], f["op99"] = statistics.median(oc), pct(oc, 0.99)
    return f


def line(label, f):
    out = [label, f"median {f['med']:.1f}", f"mean {f['mean']:.1f}", f"p99 {f['p99']:.1f} ms",
           f"p99/med {f['p99'] / f['med']:.2f}", f"mean/med {f['mean'] / f['med']:.2f}",
           f"model {f['mmed']:.1f}/{f['mmean']:.1f}/{f['mp99']:.1f} ms, p99/med {f['mp99'] / f['mmed']:.2f}, "
           f"mean/med {f['mmean'] / f['mmed']:.2f}",
           f"|V| {f['V']:.1f}", f"ids/frame {f['ids']:.1f}", f"saved {f['saved']:.1f}%", f"B/frame {f['B']:.0f}",
           f"max |V| {f['maxV']:.0f}"]
    if "Bfull" in f:
        out.append(f"full-sets B/frame {f['Bfull']:.0f}")
    if "pvs" in f:
        out.append(f"PVS/exact {f['pvs']:.2f} (max {f['pvsmax']:.1f})")
    if "exact_saved" in f:
        out.append(f"exact set's ids saved {f['exact_saved']:.1f}%")
    if "omed" in f:
        out.append(f"oracle {f['omed']:.1f}/{f['op99']:.1f} ms, p99/med {f['op99'] / f['omed']:.2f}")
    return " | ".join(out)


def table(before, after):
    labels = ["c45walk", "c45street", "c20walk", "c20street", "duplex"]
    print("| walk | size | τ | interval p99/med | interval mean/med | model p99/med | model mean/med | model median ms "
          "| ids/frame | ids saved | B/frame (full sets) | PVS/exact |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    arrow = lambda a, b, fmt: f"{fmt.format(a)} → {fmt.format(b)}"
    for label in labels:
        for size in (512, 1024):
            for tau in (0, 1):
                name = f"{label}_{size}_t{tau}"
                ex = f"out/sp/exact1/{label}_{size}"
                if not (os.path.exists(f"{before}/{name}/stats.csv") and os.path.exists(f"{after}/{name}/stats.csv")):
                    continue
                b = figures(f"{before}/{name}", ex, 1)
                a = figures(f"{after}/{name}", ex, 1)
                bytes_cell = arrow(b["B"], a["B"], "{:.0f}")
                if "Bfull" in b and "Bfull" in a:
                    bytes_cell += f" ({b['Bfull']:.0f} → {a['Bfull']:.0f})"
                print(f"| {label} | {size}² | {tau} | {arrow(b['p99'] / b['med'], a['p99'] / a['med'], '{:.1f}')} "
                      f"| {arrow(b['mean'] / b['med'], a['mean'] / a['med'], '{:.2f}')} "
                      f"| {arrow(b['mp99'] / b['mmed'], a['mp99'] / a['mmed'], '{:.2f}')} "
                      f"| {arrow(b['mmean'] / b['mmed'], a['mmean'] / a['mmed'], '{:.2f}')} "
                      f"| {arrow(b['mmed'], a['mmed'], '{:.1f}')} "
                      f"| {arrow(b['ids'], a['ids'], '{:.1f}')} | {arrow(b['saved'], a['saved'], '{:.0f}')} % "
                      f"| {bytes_cell} | {arrow(b.get('pvs', float('nan')), a.get('pvs', float('nan')), '{:.2f}')} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", nargs="?")
    ap.add_argument("--table", nargs=2, metavar=("BEFORE", "AFTER"))
    ap.add_argument("--exact")
    ap.add_argument("--exact-every", type=int, default=1)
    ap.add_argument("--label", default="")
    ap.add_argument("--dat", help="write frame, interval ms, model ms, |V|, ids sent per line here")
    a = ap.parse_args()
    if a.table:
        table(*a.table)
        return
    if not a.run:
        ap.error("RUN_DIR or --table BEFORE AFTER")
    if a.dat:
        r = rows(a.run)[1:]
        with open(a.dat, "w") as f:
            f.write("# frame interval_ms model_ms visible ids_sent\n")
            for x, m in zip(r, model_ms(r)):
                f.write(f"{x['frame']:.0f} {x['frame_interval_ms']:.3f} {m:.3f} {x['visible']:.0f} "
                        f"{x['added'] + x['removed']:.0f}\n")
    print(line(a.label or a.run, figures(a.run, a.exact, a.exact_every)))


if __name__ == "__main__":
    main()
