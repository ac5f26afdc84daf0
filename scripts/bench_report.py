#!/usr/bin/env python3
"""Aggregates a scripts/bench.sh run into OUT/bench.csv, OUT/bench.md and OUT/per_frame.dat (plots).

usage: bench_report.py OUT SCENE PATH WIDTH HEIGHT [--model-delay-ms D] [--model-gbit G] [--lookahead L]
       bench_report.py --check-model DIR [--model-delay-ms D] ...  (one cluster run's stats.csv: the
       model against the frame interval it measured, e.g. a run with --netns --link D:RATE)

Reads OUT/<method>/stats.csv for every method and OUT/<method>/wrong.txt (the summary line of
frame_diff against the method's own brute force: "frames=N differing_pixels=P max_frame_fraction=F").

The three-machine model (model_ms_three_machines) is the frame time with one machine per process,
from each process's CPU time per stage (process CPU clock: llvmpipe's threads included), the link
delay D (one way, per link; 0 on loopback) and the bytes at G Gbit/s. Per frame f of the switch:
  max( HC(f) + D + bytes(f)/G + OR_tail(f+1),   HC(f) waits for EOF(f-1): the chain of HCs
       (HC(f) + OR(f)) / 2,                     each node does one OR and one HC every 2 frames
       RVG(f),                                  the display client's CPU for the frame
       (D + OR(f) - OR_tail(f)) / (L - 1) )     camera f reaches its node 2D after EOF(f-L) left
and the mean over frames. GigaWalk: max(server OR + HC, RVG, 2D / (L - 1)). One process: its CPU.
"""
import argparse
import csv
import os
import statistics

REFERENCE = [("none", "no culling"), ("frustum", "frustum culling"),
             ("stop-and-wait", "occlusion queries, stop-and-wait"), ("chc", "occlusion queries, CHC")]
GIGAWALK = ("gigawalk", "depth readback + software HZB (Distributed GigaWalk)")
SWITCH = ("switch", "occlusion switch")
OSG = [("osg_none", "OpenSceneGraph, no culling"), ("osg_frustum", "OpenSceneGraph, frustum culling"),
       ("osg_oqn", "OpenSceneGraph, OcclusionQueryNode")]

CSV_COLUMNS = ["method", "processes", "frames", "mean_ms", "median_ms", "mean_fps", "median_fps",
               "fps_ratio_to_none", "fps_ratio_to_gigawalk", "triangles", "pvs_nodes", "pvs_exact_ratio",
               "wrong_pixels", "worst_frame_wrong_fraction", "bytes_per_frame", "stage_ms_hc", "stage_ms_or",
               "stage_ms_rvg", "cpu_ms_per_frame", "cpu_ms_per_frame_hc", "cpu_ms_per_frame_or",
               "cpu_ms_per_frame_or_tail", "cpu_ms_per_frame_rvg", "model_ms_three_machines"]


def number(v):
    try:
        return float(v)
    except ValueError:
        return None


def read_rows(path):
    """stats.csv as a list of {column: float} (empty and text cells, e.g. the cluster's mode, left out)."""
    with open(path) as f:
        return [{k: x for k, v in r.items() if v not in ("", None) and (x := number(v)) is not None}
                for r in csv.DictReader(f)]


def read_wrong(path):
    """(differing pixels, worst frame's differing fraction) from frame_diff's summary line, or None."""
    if not os.path.exists(path):
        return None
    with open(path) as f:
        fields = dict(p.split("=", 1) for p in f.read().split() if "=" in p)
    if "differing_pixels" not in fields:
        return None
    return int(fields["differing_pixels"]), float(fields["max_frame_fraction"])


def mean_of(rows, column):
    values = [r[column] for r in rows if column in r]
    return statistics.mean(values) if values else None


def change(new, old, unit):
    """How `new` compares with `old` in words: "52 % fewer ids", "70 % more ids", "as many ids"."""
    if old == 0:
        return f"as many {unit}" if new == 0 else f"{new:.1f} {unit} more (the other sends none)"
    pct = 100.0 * (new - old) / old
    if round(pct) == 0:
        return f"as many {unit}"
    return f"{abs(pct):.0f} % {'more' if pct > 0 else 'fewer'} {unit}"


CPU_STAGES = ("hc_cpu_ms", "or_cpu_ms", "or_tail_cpu_ms", "rvg_frame_cpu_ms")
WALL_STAGES = ("hc_ms", "or_ms", "or_tail_ms", "rvg_ms")  # what this machine gave each stage


def switch_model_ms(rows, delay_ms, gbit, lookahead, stages=CPU_STAGES):
    """Mean over frames of the three-machine frame time (see the module doc); None without the columns."""
    if not rows or any(c not in rows[0] for c in stages):
        return None
    hc, orr, tail, rvg = stages
    times = []
    for i, r in enumerate(rows):
        transfer_ms = r.get("bytes_received", 0) * 8 / (gbit * 1e9) * 1e3
        terms = [(r[hc] + r[orr]) / 2, r[rvg], (delay_ms + r[orr] - r[tail]) / (lookahead - 1)]
        if i + 1 < len(rows):
            terms.append(r[hc] + delay_ms + transfer_ms + rows[i + 1][tail])
        times.append(max(terms))
    return statistics.mean(times)


def gigawalk_model_ms(rows, delay_ms, gbit, lookahead):
    need = ("hc_cpu_ms", "or_cpu_ms", "rvg_frame_cpu_ms")
    if not rows or any(c not in rows[0] for c in need):
        return None
    return statistics.mean(max(r["hc_cpu_ms"] + r["or_cpu_ms"] + r.get("bytes_received", 0) * 8 / (gbit * 1e9) * 1e3,
                               r["rvg_frame_cpu_ms"], 2 * delay_ms / (lookahead - 1)) for r in rows)


def pvs_exact_ratio(nodes, exact):
    n = min(len(nodes), len(exact))
    if n == 0 or "exact_visible" not in exact[0]:
        return None
    # A frame that sees nothing and draws nothing is exact (ratio 1), not a ratio of 0.
    return statistics.mean(1.0 if nodes[i] == 0 and exact[i]["exact_visible"] == 0
                           else nodes[i] / max(exact[i]["exact_visible"], 1) for i in range(n))


def summarize(out, delay_ms=0.0, gbit=1.0, lookahead=2):
    """One dict per method present in OUT, in table order."""
    exact = read_rows(f"{out}/none/stats.csv")
    results = []

    def add(key, label, procs, rows, frame_ms, nodes, tris, wrong, **extra):
        r = dict(method=key, label=label, processes=procs, frames=len(rows), frame_ms=frame_ms,
                 mean_ms=statistics.mean(frame_ms), median_ms=statistics.median(frame_ms),
                 mean_fps=1000 * len(frame_ms) / sum(frame_ms), median_fps=1000 / statistics.median(frame_ms),
                 triangles=statistics.mean(tris) if tris else None,
                 pvs_nodes=statistics.mean(nodes) if nodes else None,
                 pvs_exact_ratio=pvs_exact_ratio(nodes, exact) if nodes else None,
                 wrong_pixels=wrong[0] if wrong else None, worst_frame_wrong_fraction=wrong[1] if wrong else None,
                 bytes_per_frame=0.0, stage_ms_hc=None, stage_ms_or=None, stage_ms_rvg=None,
                 cpu_ms_per_frame=None, cpu_ms_per_frame_hc=None, cpu_ms_per_frame_or=None,
                 cpu_ms_per_frame_or_tail=None, cpu_ms_per_frame_rvg=None, model_ms_three_machines=None)
        r.update(extra)
        results.append(r)

    for key, label in REFERENCE:
        if not os.path.exists(f"{out}/{key}/stats.csv"):
            continue
        rows = read_rows(f"{out}/{key}/stats.csv")
        cpu = mean_of(rows, "cpu_ms")
        wrong = (0, 0.0) if key == "none" else read_wrong(f"{out}/{key}/wrong.txt")
        add(key, label, 1, rows, [x["render_ms"] for x in rows], [x["nodes_drawn"] for x in rows],
            [x["triangles_drawn"] for x in rows], wrong, cpu_ms_per_frame=cpu, cpu_ms_per_frame_rvg=cpu,
            model_ms_three_machines=cpu)
    for (key, label), procs in ((GIGAWALK, 2), (SWITCH, 3)):
        if not os.path.exists(f"{out}/{key}/stats.csv"):
            continue
        rows = read_rows(f"{out}/{key}/stats.csv")
        hc, orr, tail, rvg = (mean_of(rows, c) for c in ("hc_cpu_ms", "or_cpu_ms", "or_tail_cpu_ms", "rvg_frame_cpu_ms"))
        model = (switch_model_ms if procs == 3 else gigawalk_model_ms)(rows, delay_ms, gbit, lookahead)
        add(key, label, procs, rows, [x["frame_interval_ms"] for x in rows], [x["visible"] for x in rows],
            [x["triangles"] for x in rows], read_wrong(f"{out}/{key}/wrong.txt"),
            bytes_per_frame=mean_of(rows, "bytes_received"), stage_ms_hc=mean_of(rows, "hc_ms"),
            stage_ms_or=mean_of(rows, "or_ms"), stage_ms_rvg=mean_of(rows, "rvg_ms"),
            cpu_ms_per_frame=None if None in (hc, orr, rvg) else hc + orr + rvg, cpu_ms_per_frame_hc=hc,
            cpu_ms_per_frame_or=orr, cpu_ms_per_frame_or_tail=tail if procs == 3 else None,
            cpu_ms_per_frame_rvg=rvg, model_ms_three_machines=model)
    for key, label in OSG:
        if not os.path.exists(f"{out}/{key}/stats.csv"):
            continue
        rows = read_rows(f"{out}/{key}/stats.csv")
        wrong = (0, 0.0) if key == "osg_none" else read_wrong(f"{out}/{key}/wrong.txt")
        add(key, label, 1, rows, [x["render_ms"] for x in rows], [], [], wrong,
            objects_drawn=mean_of(rows, "objects_drawn"))
    return results


def incremental(out):
    """(ids/frame, bytes/frame) of the switch run's diffs and of the whole visible sets it would have
    sent instead (stats.csv's visible and full_set_bytes), or None."""
    if not os.path.exists(f"{out}/switch/stats.csv"):
        return None
    inc = read_rows(f"{out}/switch/stats.csv")
    ids = statistics.mean(x["added"] + x["removed"] for x in inc)
    return ids, mean_of(inc, "bytes_received"), mean_of(inc, "visible"), mean_of(inc, "full_set_bytes")


def fmt(v, digits=2):
    return "" if v is None else f"{v:.{digits}f}"


def cell(v, digits=1):
    return "-" if v is None else f"{v:.{digits}f}"


def ratio(r, base):
    return None if base is None or base == 0 else r["mean_fps"] / base


def bases(results):
    by = {r["method"]: r for r in results}
    none = by.get("none", {}).get("mean_fps")
    gw = by.get("gigawalk", {}).get("mean_fps")
    osg_none = by.get("osg_none", {}).get("mean_fps")
    return none, gw, osg_none


def write_csv(out, results):
    none, gw, osg_none = bases(results)
    with open(f"{out}/bench.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(CSV_COLUMNS)
        for r in results:
            own_none = osg_none if r["method"].startswith("osg_") else none
            w.writerow([r["method"], r["processes"], r["frames"], fmt(r["mean_ms"]), fmt(r["median_ms"]),
                        fmt(r["mean_fps"]), fmt(r["median_fps"]), fmt(ratio(r, own_none)),
                        "" if r["method"].startswith("osg_") else fmt(ratio(r, gw)), fmt(r["triangles"], 0),
                        fmt(r["pvs_nodes"], 1), fmt(r["pvs_exact_ratio"]),
                        "" if r["wrong_pixels"] is None else r["wrong_pixels"],
                        "" if r["worst_frame_wrong_fraction"] is None else f"{r['worst_frame_wrong_fraction']:.6f}",
                        fmt(r["bytes_per_frame"], 0), fmt(r["stage_ms_hc"]), fmt(r["stage_ms_or"]),
                        fmt(r["stage_ms_rvg"]), fmt(r["cpu_ms_per_frame"]), fmt(r["cpu_ms_per_frame_hc"]),
                        fmt(r["cpu_ms_per_frame_or"]), fmt(r["cpu_ms_per_frame_or_tail"]),
                        fmt(r["cpu_ms_per_frame_rvg"]), fmt(r["model_ms_three_machines"])])


def wrong_cell(r):
    if r["method"] in ("none", "osg_none"):
        return "brute force"
    if r["wrong_pixels"] is None:
        return "-"
    return f"{r['wrong_pixels']} / {100 * r['worst_frame_wrong_fraction']:.2f} %"


def cpu_cell(r):
    if r["processes"] == 1:
        return cell(r["cpu_ms_per_frame_rvg"])
    if r["cpu_ms_per_frame_hc"] is None:
        return "-"
    if r["processes"] == 2:
        return (f"server {r['cpu_ms_per_frame_or'] + r['cpu_ms_per_frame_hc']:.1f} (render/readback "
                f"{r['cpu_ms_per_frame_or']:.1f} + HZB {r['cpu_ms_per_frame_hc']:.2f}), RVG {r['cpu_ms_per_frame_rvg']:.1f}")
    return (f"HC {r['cpu_ms_per_frame_hc']:.1f}, OR {r['cpu_ms_per_frame_or']:.1f} (tail "
            f"{r['cpu_ms_per_frame_or_tail']:.1f}), RVG {r['cpu_ms_per_frame_rvg']:.1f}")


def write_md(out, results, scene, path, width, height, delay_ms, gbit):
    none, gw, osg_none = bases(results)
    exact = read_rows(f"{out}/none/stats.csv")
    with open(f"{out}/bench.md", "w") as f:
        f.write(f"Scene `{scene}`, path `{path}`, {width}x{height}, {len(exact)} frames, llvmpipe, all processes on one "
                f"2-core machine (LP_NUM_THREADS=1).")
        if exact and "exact_visible" in exact[0]:
            f.write(f" Exact visibility (item buffer): {mean_of(exact, 'exact_visible'):.1f} nodes, "
                    f"{mean_of(exact, 'exact_triangles'):.0f} triangles per frame.")
        f.write("\n\n| method | procs | fps mean | fps median | × none | × GigaWalk | triangles/frame | PVS nodes | "
                "PVS/exact | wrong pixels (total / worst frame) | bytes/frame | CPU ms/frame (per process) | "
                "model ms/frame, one machine per process |\n")
        f.write("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n")
        for r in results:
            osg = r["method"].startswith("osg_")
            own_none = osg_none if osg else none
            f.write(f"| {r['label']} | {r['processes']} | {r['mean_fps']:.1f} | {r['median_fps']:.1f} | "
                    f"{cell(ratio(r, own_none), 2)} | {'-' if osg else cell(ratio(r, gw), 2)} | "
                    f"{cell(r['triangles'], 0)} | "
                    f"{cell(r.get('objects_drawn'), 1) + ' objects' if osg else cell(r['pvs_nodes'])} | "
                    f"{cell(r['pvs_exact_ratio'], 2)} | {wrong_cell(r)} | {cell(r['bytes_per_frame'], 0)} | "
                    f"{cpu_cell(r)} | {cell(r['model_ms_three_machines'])} |\n")
        f.write(f"\nfps: wall clock on this machine (the processes share 2 cores). Wrong pixels: differing from "
                f"the same renderer's brute force (no culling) in the method's own frames, threshold 0. CPU: process "
                f"CPU clock (all threads, llvmpipe's included) per frame; for the switch HC and OR per frame (each "
                f"node does every other frame), OR tail = the OR work after the other node's last diff chunk "
                f"arrived. Model: frame time with one machine per process from those CPU times, {delay_ms:g} ms "
                f"link delay and the bytes at {gbit:g} Gbit/s (scripts/bench_report.py).")
        if any(r["method"].startswith("osg_") for r in results):
            f.write(" OpenSceneGraph rows: osg_peer (../shared/peers/osg) on the same path and viewport, "
                    "× none against its own brute force, objects = mesh instances its cull traversal reached.")
        f.write("\n")
        inc = incremental(out)
        if inc:
            inc_ids, inc_bytes, full_ids, full_bytes = inc
            f.write(f"Incremental transmission: {inc_ids:.1f} ids/frame ({inc_bytes:.0f} B/frame) vs full sets "
                    f"{full_ids:.1f} ids/frame ({full_bytes:.0f} B/frame): {change(inc_ids, full_ids, 'ids')}, "
                    f"{change(inc_bytes, full_bytes, 'bytes')} (paper: 93 % fewer on the tanker path).\n")


def write_per_frame(out, results):
    keys = [m for m, _ in REFERENCE] + [GIGAWALK[0], SWITCH[0]]
    by = {r["method"]: r for r in results}
    if any(k not in by for k in keys) or not os.path.exists(f"{out}/switch/stats.csv"):
        return
    inc = read_rows(f"{out}/switch/stats.csv")
    with open(f"{out}/per_frame.dat", "w") as f:
        f.write("# frame " + " ".join(f"fps_{k}" for k in keys) + " ids_incremental ids_full\n")
        n = min(min(len(by[k]["frame_ms"]) for k in keys), len(inc))
        for i in range(n):
            fps = " ".join(f"{1000 / max(by[k]['frame_ms'][i], 1e-6):.2f}" for k in keys)
            f.write(f"{i} {fps} {inc[i]['added'] + inc[i]['removed']:.0f} {inc[i]['visible']:.0f}\n")


def check_model(run_dir, delay_ms, gbit, lookahead):
    """The model next to what one cluster run measured (frames 0-1 left out: they send the whole set)."""
    rows = read_rows(f"{run_dir}/stats.csv")[2:]
    model = switch_model_ms(rows, delay_ms, gbit, lookahead)
    if model is None:
        raise SystemExit(f"error: {run_dir}/stats.csv has no CPU columns (a run of an older build?)")
    wall = switch_model_ms(rows, delay_ms, gbit, lookahead, WALL_STAGES)
    measured = statistics.mean(r["frame_interval_ms"] for r in rows)
    median = statistics.median(r["frame_interval_ms"] for r in rows)
    print(f"{run_dir}: {len(rows)} frames, measured {measured:.2f} ms/frame (median {median:.2f}); model "
          f"({delay_ms:g} ms links) from CPU times {model:.2f} ms/frame (x{model / measured:.2f})"
          + ("" if wall is None else f", from this machine's wall-clock stage times {wall:.2f} (x{wall / measured:.2f})")
          + "; CPU per frame HC "
          f"{mean_of(rows, 'hc_cpu_ms'):.2f}, OR {mean_of(rows, 'or_cpu_ms'):.2f} (tail {mean_of(rows, 'or_tail_cpu_ms'):.2f}), "
          f"RVG {mean_of(rows, 'rvg_frame_cpu_ms'):.2f}; wall HC {mean_of(rows, 'hc_ms'):.2f}, OR {mean_of(rows, 'or_ms'):.2f}")


def main(argv=None):
    if argv is None:
        import sys
        argv = sys.argv[1:]
    if argv and argv[0] == "--check-model":
        c = argparse.ArgumentParser(description="the three-machine model against one cluster run")
        c.add_argument("--check-model", dest="run_dir", required=True)
        c.add_argument("--model-delay-ms", type=float, default=0.0)
        c.add_argument("--model-gbit", type=float, default=1.0)
        c.add_argument("--lookahead", type=int, default=2)
        a = c.parse_args(argv)
        return check_model(a.run_dir, a.model_delay_ms, a.model_gbit, a.lookahead)
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("out")
    p.add_argument("scene")
    p.add_argument("path")
    p.add_argument("width")
    p.add_argument("height")
    p.add_argument("--model-delay-ms", type=float, default=0.0, help="one-way delay per link for the model")
    p.add_argument("--model-gbit", type=float, default=1.0, help="link rate for the model, Gbit/s")
    p.add_argument("--lookahead", type=int, default=2, help="the render client's camera lookahead (lockstep)")
    a = p.parse_args(argv)
    if a.lookahead < 2:
        p.error("--lookahead must be at least 2")
    results = summarize(a.out, a.model_delay_ms, a.model_gbit, a.lookahead)
    write_csv(a.out, results)
    write_md(a.out, results, a.scene, a.path, a.width, a.height, a.model_delay_ms, a.model_gbit)
    write_per_frame(a.out, results)


if __name__ == "__main__":
    main()
