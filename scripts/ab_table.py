#!/usr/bin/env python3
"""Two checkouts' clusters on the same views, paired: for every scene, path and size, the cluster
of checkout A (scripts/cluster.sh of that tree, with its build/bin) then B's, --pairs times
(A B A B ...), --images off, tau 0. Each figure is the median frame interval at the render
client's display (stats.csv frame_interval_ms, frames --skip on) of one run, then the median over
the pairs; the ratio is B over A. Use it to show that a change made no view slower: run it on a
quiet machine. Prints a markdown table and writes it to OUT/ab.md. Asserts nothing about speed.

  scripts/ab_table.py --a DIR --b DIR --scene S --path P [--scene S2 --path P2 ...]
                      [--sizes 512,1024] [--pairs N] [--skip K] [--out DIR] [-- cluster.sh flags]
"""
import argparse
import csv
import os
import statistics
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def die(msg):
    sys.exit(f"ab_table: error: {msg}")


def interval(stats, skip):
    with open(stats) as f:
        rows = list(csv.DictReader(f))
    if not rows or "frame_interval_ms" not in rows[0]:
        die(f"{stats}: no column frame_interval_ms")
    values = [float(r["frame_interval_ms"]) for r in rows[skip:]]
    if not values:
        die(f"{stats}: no frames from frame {skip} on")
    return statistics.median(values)


def cluster(tree, scene, path, size, out, extra):
    cmd = [os.path.join(tree, "scripts", "cluster.sh"), "--scene", scene, "--path", path, "--width", size,
           "--height", size, "--images", "off", "--on-node-failure", "exit", "--out", out, *extra]
    env = dict(os.environ)
    env.pop("OCC_BIN", None)  # each tree's own binaries
    with open(out + ".log", "w") as f:
        p = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT, env=env)
    if p.returncode != 0:
        die(f"{' '.join(cmd)} failed (exit {p.returncode}); its output: {out}.log")
    return os.path.join(out, "stats.csv")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--a", required=True, help="checkout A (before)")
    ap.add_argument("--b", required=True, help="checkout B (after)")
    ap.add_argument("--scene", action="append", default=[])
    ap.add_argument("--path", action="append", default=[])
    ap.add_argument("--sizes", default="512")
    ap.add_argument("--pairs", type=int, default=2)
    ap.add_argument("--skip", type=int, default=3)
    ap.add_argument("--out", default="out/ab")
    ap.add_argument("cluster_args", nargs="*", help="after --: more scripts/cluster.sh flags")
    args = ap.parse_args()
    if len(args.scene) != len(args.path) or not args.scene:
        die("give --scene and --path in pairs, at least one")
    if args.pairs < 1:
        die(f"--pairs {args.pairs}: at least 1")
    for tree in (args.a, args.b):
        if not os.access(os.path.join(tree, "scripts", "cluster.sh"), os.X_OK):
            die(f"{tree}: no scripts/cluster.sh")
    sizes = [s.strip() for s in args.sizes.split(",") if s.strip()]
    for s in sizes:
        if not s.isdigit() or not 16 <= int(s) <= 8192:
            die(f"--sizes: '{s}' is not a size in pixels (16..8192)")
    os.makedirs(args.out, exist_ok=True)
    lines = ["| scene, path | size | A ms | B ms | B / A |", "|---|---|---|---|---|"]
    for scene, path in zip(args.scene, args.path):
        for size in sizes:
            figs = {"a": [], "b": []}
            for i in range(args.pairs):
                for side in ("a", "b"):
                    tree = getattr(args, side)
                    name = f"{os.path.basename(scene).split('.')[0].replace(':', '_')}_{path.replace(':', '_')}_{size}"
                    d = os.path.join(args.out, f"{name}_{side}{i}")
                    figs[side].append(interval(cluster(tree, scene, path, size, d, args.cluster_args), args.skip))
            a, b = statistics.median(figs["a"]), statistics.median(figs["b"])
            row = f"| {os.path.basename(scene)} {path} | {size}^2 | {a:.2f} | {b:.2f} | {b / a:.2f} |"
            print(row, flush=True)
            lines.append(row)
    with open(os.path.join(args.out, "ab.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
