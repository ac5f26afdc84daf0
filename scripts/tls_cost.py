#!/usr/bin/env python3
"""What TLS costs per frame (docs/security.md): scripts/cluster.sh in pairs, --no-key (plain TCP)
then with its fresh key (TLS 1.3), one after the other: A B A B ...

Per run: CPU time of every process of the cluster (user + sys of the children cluster.sh waited
for: both switch nodes and the render client, start-up included) per frame, and the bytes per
frame on the render client's links as the two nodes count them (their "link to the render client"
lines): messages and bytes on the wire (TCP payload), down (nodes -> client) and up. One line per
run, then the TLS/plain ratios per pair and their mean.

  scripts/tls_cost.py [--pairs N] [--path P] [--out DIR] [cluster.sh args ...]
"""
import argparse
import re
import resource
import subprocess
import sys

LINK = re.compile(r"link to the render client \(([^)]*)\): (\d+) B of messages sent as (\d+) B on the wire, "
                  r"(\d+) B received as (\d+) B")


def run(arm, out, extra):
    cmd = ["scripts/cluster.sh", "--out", out, *extra] + (["--no-key"] if arm == "plain" else [])
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    p = subprocess.run(cmd, capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    summary = re.search(r"summary: frames=(\d+)", p.stdout + p.stderr)
    if p.returncode != 0 or not summary:
        sys.exit(f"error: {' '.join(cmd)} failed (exit {p.returncode}): see {out}")
    frames = int(summary.group(1))
    cpu = after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime
    r = {"arm": arm, "frames": frames, "cpu_ms_per_frame": 1000 * cpu / frames, "link": set(),
         "msg_down": 0.0, "wire_down": 0.0, "msg_up": 0.0, "wire_up": 0.0}
    for n in (0, 1):
        m = LINK.search(open(f"{out}/node{n}.log").read())
        if not m:
            sys.exit(f"error: {out}/node{n}.log has no 'link to the render client' line")
        r["link"].add(m.group(1))
        for key, g in (("msg_down", 2), ("wire_down", 3), ("msg_up", 4), ("wire_up", 5)):
            r[key] += int(m.group(g)) / frames
    r["link"] = ",".join(sorted(r["link"]))
    return r


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--pairs", type=int, default=3)
    ap.add_argument("--path", default="walk:2000")
    ap.add_argument("--out", default="out/tls_cost")
    args, extra = ap.parse_known_args()
    extra = ["--scene", "city", "--path", args.path, "--width", "256", "--height", "256", "--images", "off", *extra]
    fields = ("cpu_ms_per_frame", "wire_down", "wire_up")
    ratios = {f: [] for f in fields}
    for i in range(args.pairs):
        pair = {arm: run(arm, f"{args.out}/{arm}{i}", extra) for arm in ("plain", "tls")}
        for r in pair.values():
            print(f"{r['arm']:5} ({r['link']}): frames={r['frames']} cpu_ms_per_frame={r['cpu_ms_per_frame']:.3f} "
                  f"down: {r['msg_down']:.1f} B of messages, {r['wire_down']:.1f} B on the wire; "
                  f"up: {r['msg_up']:.1f} B, {r['wire_up']:.1f} B", flush=True)
        for f in fields:
            ratios[f].append(pair["tls"][f] / pair["plain"][f])
        print("pair %d: TLS/plain " % i + " ".join(f"{f}={ratios[f][-1]:.3f}" for f in fields), flush=True)
    print("mean TLS/plain " + " ".join(f"{f}={sum(v) / len(v):.3f}" for f, v in ratios.items()))


if __name__ == "__main__":
    main()
