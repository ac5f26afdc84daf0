#!/usr/bin/env python3
"""Aggregates a scripts/bench.sh run: OUT/bench.csv, OUT/bench.md and OUT/per_frame.dat (for the plots)."""
import csv
import statistics
import sys

out, scene, path, width, height = sys.argv[1:6]


def rows(method):
    with open(f"{out}/{method}/stats.csv") as f:
        return [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]


exact = rows("none")
methods = [("none", "no culling", 1), ("frustum", "frustum culling", 1), ("stop-and-wait", "occlusion queries, stop-and-wait", 1),
           ("chc", "occlusion queries, CHC", 1), ("gigawalk", "depth readback + software HZB (Distributed GigaWalk)", 2),
           ("switch", "occlusion switch", 3)]
results = []
per_frame = {}
for key, label, procs in methods:
    r = rows(key)
    if procs == 1:
        frame_ms = [x["render_ms"] for x in r]
        nodes = [x["nodes_drawn"] for x in r]
        tris = [x["triangles_drawn"] for x in r]
        bytes_pf = 0.0
        stage = "-"
        machines_ms = statistics.mean(frame_ms)
    else:
        frame_ms = [x["frame_interval_ms"] for x in r]
        nodes = [x["visible"] for x in r]
        tris = [x["triangles"] for x in r]
        bytes_pf = statistics.mean(x["bytes_received"] for x in r)
        hc, orr, rvg = (statistics.mean(x[c] for x in r) for c in ("hc_ms", "or_ms", "rvg_ms"))
        # With one machine per process the frame rate is set by the slowest stage; the bytes on the
        # wire add (1 Gbit/s assumed) transfer time.
        transfer_ms = bytes_pf * 8 / 1e9 * 1e3
        if procs == 2:
            machines_ms = max(hc + orr, rvg) + transfer_ms
            stage = f"server {hc + orr:.1f} (HZB {hc:.2f} + render/readback {orr:.1f}), RVG {rvg:.1f}"
        else:
            machines_ms = max(hc, orr, rvg) + transfer_ms
            stage = f"HC {hc:.1f}, OR {orr:.1f}, RVG {rvg:.1f}"
    per_frame[key] = frame_ms
    n = min(len(nodes), len(exact))
    # A frame that sees nothing and draws nothing is exact (ratio 1), not a ratio of 0.
    pvs_ratio = statistics.mean(1.0 if nodes[i] == 0 and exact[i]["exact_visible"] == 0
                                else nodes[i] / max(exact[i]["exact_visible"], 1) for i in range(n))
    results.append(dict(method=key, label=label, processes=procs, frames=len(r),
                        mean_ms=statistics.mean(frame_ms), median_ms=statistics.median(frame_ms),
                        mean_fps=1000 * len(frame_ms) / sum(frame_ms), median_fps=1000 / statistics.median(frame_ms),
                        triangles=statistics.mean(tris), pvs_nodes=statistics.mean(nodes), pvs_exact_ratio=pvs_ratio,
                        bytes_per_frame=bytes_pf, stage_ms=stage, separate_machines_ms=machines_ms))
base = results[0]["mean_fps"]
gw = results[4]["mean_fps"]
full = rows("switch_full")
inc = rows("switch")
inc_bytes = statistics.mean(x["bytes_received"] for x in inc)
full_bytes = statistics.mean(x["bytes_received"] for x in full)
inc_ids = statistics.mean(x["added"] + x["removed"] for x in inc)
full_ids = statistics.mean(x["added"] + x["removed"] for x in full)

with open(f"{out}/bench.csv", "w", newline="") as f:
    cols = ["method", "processes", "frames", "mean_ms", "median_ms", "mean_fps", "median_fps", "fps_ratio_to_none",
            "fps_ratio_to_gigawalk", "triangles", "pvs_nodes", "pvs_exact_ratio", "bytes_per_frame",
            "separate_machines_ms"]
    w = csv.writer(f)
    w.writerow(cols)
    for r in results:
        w.writerow([r["method"], r["processes"], r["frames"], f"{r['mean_ms']:.2f}", f"{r['median_ms']:.2f}",
                    f"{r['mean_fps']:.2f}", f"{r['median_fps']:.2f}", f"{r['mean_fps'] / base:.2f}",
                    f"{r['mean_fps'] / gw:.2f}", f"{r['triangles']:.0f}", f"{r['pvs_nodes']:.1f}",
                    f"{r['pvs_exact_ratio']:.2f}", f"{r['bytes_per_frame']:.0f}", f"{r['separate_machines_ms']:.2f}"])

exact_nodes = statistics.mean(x["exact_visible"] for x in exact)
exact_tris = statistics.mean(x["exact_triangles"] for x in exact)
with open(f"{out}/bench.md", "w") as f:
    f.write(f"Scene `{scene}`, path `{path}`, {width}x{height}, {len(exact)} frames, llvmpipe, all processes on one "
            f"2-core machine (LP_NUM_THREADS=1). Exact visibility (item buffer): {exact_nodes:.1f} nodes, "
            f"{exact_tris:.0f} triangles per frame.\n\n")
    f.write("| method | procs | fps mean | fps median | × none | × GigaWalk | triangles/frame | PVS nodes | PVS/exact | "
            "bytes/frame | stage ms (per process) | est. ms/frame, one machine per process |\n")
    f.write("|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    for r in results:
        f.write(f"| {r['label']} | {r['processes']} | {r['mean_fps']:.1f} | {r['median_fps']:.1f} | "
                f"{r['mean_fps'] / base:.2f} | {r['mean_fps'] / gw:.2f} | {r['triangles']:.0f} | {r['pvs_nodes']:.1f} | "
                f"{r['pvs_exact_ratio']:.2f} | {r['bytes_per_frame']:.0f} | {r['stage_ms']} | "
                f"{r['separate_machines_ms']:.1f} |\n")
    f.write(f"\nfps: measured wall clock on this machine (3 processes share 2 cores). The last column estimates "
            f"the frame time with one machine per process: the slowest stage plus the bytes at 1 Gbit/s.\n"
            f"Incremental transmission: {inc_ids:.1f} ids/frame ({inc_bytes:.0f} B/frame) vs full sets "
            f"{full_ids:.1f} ids/frame ({full_bytes:.0f} B/frame): {100 * (1 - inc_ids / max(full_ids, 1e-9)):.0f}% fewer ids "
            f"(paper: 93% on the tanker path).\n")

with open(f"{out}/per_frame.dat", "w") as f:
    keys = [m[0] for m in methods]
    f.write("# frame " + " ".join(f"fps_{k}" for k in keys) + " ids_incremental ids_full\n")
    n = min(len(v) for v in per_frame.values())
    for i in range(min(n, len(inc), len(full))):
        fps = " ".join(f"{1000 / max(per_frame[k][i], 1e-6):.2f}" for k in keys)
        f.write(f"{i} {fps} {inc[i]['added'] + inc[i]['removed']:.0f} {full[i]['added'] + full[i]['removed']:.0f}\n")
