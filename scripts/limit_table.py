#!/usr/bin/env python3
"""The cluster against the limit (docs/results.md, "cluster / oracle"): for every scene, path and
viewport given, one after another on the same cameras, at tau 0:

  oracle   a render of exactly the visible objects (render_client --cull none --exact,
           its oracle_ms column: what no culling can beat on this renderer); the same run's
           render_ms is brute force (every object, no culling)
  frustum  render_client --cull frustum (one process, hierarchical frustum culling)
  cluster  scripts/cluster.sh (two switch nodes and the render client): the frame interval at the
           render client's display

Repeats run interleaved (oracle frustum cluster, oracle frustum cluster, ...); each figure is the
median (and p99) of a run's frames from frame --skip on, then the median over the repeats. Wrong
pixels: the cluster's frames of one more run with images against brute force's (frame_diff).
PVS/exact: on the frames the switch culled with occlusion (the gate sends frustum sets where that
pays, and those are not its visible set), the triangles the render client drew over the exactly
visible ones on the same cameras, all repeats together; beside it the share of such frames. Box
floor: the same ratio for the single-process stop-and-wait baseline (render_client
--cull stop-and-wait --exact: front to back, each leaf's box queried against the depth of
everything nearer), over all frames from --skip on, one untimed run: what testing boxes cannot
prove hidden, whoever tests them. --host-cpus CORES (root): the timed runs as on hosts of CORES
cores each (scripts/lib.sh's CPU groups): each single-process render in a group of its own, the
cluster with --host-cpus (each of its three processes in one). A single-process frame's time is
then its CPU time over CORES (oracle_cpu_ms, cpu_ms), not its render's wall-clock time: a group's
quota throttles it wherever the quota runs out, so a frame's wall clock also holds the throttling
of the untimed work before it (the oracle's: its exact visibility) and leaves out what its own
render causes after it (the frustum render's); the cluster's frame interval, back to back, holds
all of its own. Prints a markdown table and writes it to OUT/limit.md (rows also in
OUT/limit.csv). Asserts nothing about speed.

  scripts/limit_table.py --scene S --path P [--scene S2 --path P2 ...] [--sizes 512,1024]
                         [--repeats N] [--skip K] [--host-cpus CORES] [--out DIR] [-- cluster.sh flags]
"""
import argparse
import csv
import os
import re
import statistics
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
LIB = os.path.join(HERE, "lib.sh")
ROOT = os.path.dirname(HERE)
BIN = os.environ.get("OCC_BIN", os.path.join(ROOT, "build", "bin"))


def die(msg):
    sys.exit(f"limit_table: error: {msg}")


def run(cmd, log):
    with open(log, "w") as f:
        p = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT)
    if p.returncode != 0:
        die(f"{' '.join(cmd)} failed (exit {p.returncode}); its output: {log}")


def column(stats, name, skip):
    with open(stats) as f:
        rows = list(csv.DictReader(f))
    if len(rows) <= skip:
        die(f"{stats}: {len(rows)} frames, fewer than --skip {skip} + 1")
    if name not in rows[0]:
        die(f"{stats}: no column {name}")
    return [float(r[name]) for r in rows[skip:]]


def single(stats, wall, cpu, args):
    """A single-process render's frame times: its column `wall` (wall clock), or with --host-cpus
    its column `cpu` (CPU time) over the group's cores (the module's docstring says why)."""
    if not args.host_cpus:
        return column(stats, wall, args.skip)
    return [c / float(args.host_cpus) for c in column(stats, cpu, args.skip)]


def p99(v):
    s = sorted(v)
    return s[min(len(s) - 1, int(0.99 * len(s)))]


def pvs_over_exact(d, skip):
    """On the cluster's frames from `skip` on that the switch culled with occlusion: the triangles
    drawn and the exactly visible ones on the same cameras (the reference's frame f is camera f);
    then the count of those frames and of all frames."""
    exact = dict(zip(column(f"{d}/none/stats.csv", "frame", 0), column(f"{d}/none/stats.csv", "exact_triangles", 0)))
    cam, occ, tri = (column(f"{d}/cluster/stats.csv", c, skip) for c in ("camera", "occlusion", "triangles"))
    culled = [(c, t) for c, o, t in zip(cam, occ, tri) if o == 1 and c in exact]
    return sum(t for _, t in culled), sum(exact[c] for c, _ in culled), sum(1 for o in occ if o == 1), len(occ)


def measure(scene, path, size, args, out):
    view = ["--width", str(size), "--height", str(size)]
    ref = [os.path.join(BIN, "render_client"), "--scene", scene, "--path", path, *view]
    # The timed runs: with --host-cpus each in a CPU group of its own (the cluster: one per process).
    timed, cluster_flags = ref, list(args.cluster_args)
    if args.host_cpus:
        timed = ["bash", "-c", 'source "$0" && occ_run_in_cpu_group "$@"', LIB, args.host_cpus, *ref]
        cluster_flags += ["--host-cpus", args.host_cpus]
    runs = {"oracle": [], "none": [], "frustum": [], "cluster": []}
    for r in range(args.repeats):
        d = os.path.join(out, f"r{r}")
        os.makedirs(d, exist_ok=True)
        print(f"limit_table: {scene} {path} {size}^2, repeat {r + 1} of {args.repeats}", file=sys.stderr)
        run(timed + ["--cull", "none", "--exact", "--images", "off", "--out", f"{d}/none"], f"{d}/none.log")
        run(timed + ["--cull", "frustum", "--images", "off", "--out", f"{d}/frustum"], f"{d}/frustum.log")
        run([os.path.join(HERE, "cluster.sh"), "--scene", scene, "--path", path, *view, "--images", "off",
             "--on-node-failure", "exit", "--out", f"{d}/cluster", *cluster_flags], f"{d}/cluster.log")
        runs["oracle"].append(single(f"{d}/none/stats.csv", "oracle_ms", "oracle_cpu_ms", args))
        runs["none"].append(single(f"{d}/none/stats.csv", "render_ms", "cpu_ms", args))
        runs["frustum"].append(single(f"{d}/frustum/stats.csv", "render_ms", "cpu_ms", args))
        runs["cluster"].append(column(f"{d}/cluster/stats.csv", "frame_interval_ms", args.skip))
    pvs = [pvs_over_exact(os.path.join(out, f"r{r}"), args.skip) for r in range(args.repeats)]
    drawn_tri, exact_tri, occlusion_frames, frames = (sum(p[k] for p in pvs) for k in range(4))
    # The box floor: one untimed run of the stop-and-wait baseline.
    run(ref + ["--cull", "stop-and-wait", "--exact", "--images", "off", "--out", f"{out}/box_floor"],
        f"{out}/box_floor.log")
    floor_drawn, floor_exact = (sum(column(f"{out}/box_floor/stats.csv", c, args.skip))
                                for c in ("triangles_drawn", "exact_triangles"))
    # Wrong pixels: one more run of each with images (PNG writing stays out of the timed runs).
    run(ref + ["--cull", "none", "--out", f"{out}/frames_none"], f"{out}/frames_none.log")
    run([os.path.join(HERE, "cluster.sh"), "--scene", scene, "--path", path, *view, "--on-node-failure", "exit",
         "--out", f"{out}/frames_cluster", *args.cluster_args], f"{out}/frames_cluster.log")
    diff = subprocess.run([os.path.join(BIN, "frame_diff"), f"{out}/frames_none", f"{out}/frames_cluster"],
                          capture_output=True, text=True)
    m = re.search(r"differing_pixels=(\d+)", diff.stdout)
    if not m:
        die(f"frame_diff printed no summary: {diff.stdout[-300:]} {diff.stderr[-300:]}")
    for d in ("frames_none", "frames_cluster"):
        for f in os.listdir(f"{out}/{d}"):
            if f.endswith(".png"):
                os.remove(f"{out}/{d}/{f}")
    fig = {k: (statistics.median(statistics.median(v) for v in vs), statistics.median(p99(v) for v in vs))
           for k, vs in runs.items()}
    return {"scene": scene, "path": path, "size": size, "repeats": args.repeats,
            **{f"{k}_median_ms": round(v[0], 2) for k, v in fig.items()},
            **{f"{k}_p99_ms": round(v[1], 2) for k, v in fig.items()},
            "cluster_over_oracle": round(fig["cluster"][0] / fig["oracle"][0], 2),
            "cluster_over_best_single": round(fig["cluster"][0] / min(fig["none"][0], fig["frustum"][0]), 2),
            "pvs_over_exact": round(drawn_tri / exact_tri, 2) if exact_tri > 0 else float("nan"),
            "occlusion_frames_pct": round(100.0 * occlusion_frames / frames),
            "box_floor": round(floor_drawn / floor_exact, 2) if floor_exact > 0 else float("nan"),
            "wrong_pixels": int(m.group(1))}


def markdown(rows):
    out = ["| scene, path | size | oracle ms | brute force ms | frustum ms | cluster ms | cluster / oracle "
           "| cluster / min(brute, frustum) | PVS / exact (frames with occlusion) | box floor | wrong px |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        mp = lambda k: f"{r[k + '_median_ms']:.2f} / {r[k + '_p99_ms']:.2f}"
        out.append(f"| {r['scene']} {r['path']} | {r['size']}^2 | {mp('oracle')} | {mp('none')} | {mp('frustum')} "
                   f"| {mp('cluster')} | {r['cluster_over_oracle']:.2f} | {r['cluster_over_best_single']:.2f} "
                   f"| {r['pvs_over_exact']:.2f} ({r['occlusion_frames_pct']} %) | {r['box_floor']:.2f} "
                   f"| {r['wrong_pixels']} |")
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", action="append", required=True, help="a --scene spec (repeat with --path)")
    ap.add_argument("--path", action="append", required=True, help="its camera path (one per --scene)")
    ap.add_argument("--sizes", default="512,1024", help="viewport sizes, square (default 512,1024)")
    ap.add_argument("--repeats", type=int, default=1, help="interleaved runs of each (default 1)")
    ap.add_argument("--skip", type=int, default=3, help="frames left out at the start (default 3)")
    ap.add_argument("--host-cpus", default="", metavar="CORES",
                    help="root: the timed runs as on hosts of CORES cores each (CPU groups; default: none)")
    ap.add_argument("--out", default="out/limit", help="output folder (default out/limit)")
    ap.add_argument("cluster_args", nargs="*", help="after --: more scripts/cluster.sh flags")
    args = ap.parse_args()
    if len(args.scene) != len(args.path):
        die(f"{len(args.scene)} --scene but {len(args.path)} --path: give one path per scene")
    if args.repeats < 1 or args.skip < 0:
        die("--repeats must be >= 1 and --skip >= 0")
    try:
        sizes = [int(s) for s in args.sizes.split(",")]
    except ValueError:
        die(f"--sizes '{args.sizes}': expected sizes like 512,1024")
    if args.host_cpus:  # checked by scripts/lib.sh, as cluster.sh checks it, before anything runs
        p = subprocess.run(["bash", "-c", 'source "$0" && occ_cpu_cores "$1" --host-cpus', LIB, args.host_cpus],
                           capture_output=True, text=True)
        if p.returncode != 0:
            die(p.stderr.strip().removeprefix("error: "))
    for b in ("render_client", "switch_node", "frame_diff"):
        if not os.access(os.path.join(BIN, b), os.X_OK):
            die(f"{BIN}/{b} not found: build first (scripts/build.sh)")
    os.environ.setdefault("LP_NUM_THREADS", "1")
    rows = []
    for i, (scene, path) in enumerate(zip(args.scene, args.path)):
        for size in sizes:
            rows.append(measure(scene, path, size, args, os.path.join(args.out, f"{i}_{size}")))
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "limit.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    table = markdown(rows)
    with open(os.path.join(args.out, "limit.md"), "w") as f:
        f.write(table + "\n")
    print(table)


if __name__ == "__main__":
    main()
