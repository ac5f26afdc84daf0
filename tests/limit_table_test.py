#!/usr/bin/env python3
"""scripts/limit_table.py, the one command that makes docs/results.md's "cluster / oracle"
table, run end to end on one small view (the office walked through its walls): its row holds every
column, the ratios are those of its own medians, the cluster's frames equal brute force's, and
neither the switch's PVS nor the box floor (stop-and-wait) draws fewer triangles than the exactly
visible ones. Bad arguments are one error line; --host-cpus runs through CPU groups. Run by ctest
(LimitTable.*) with the binaries' folder as its argument; asserts nothing about speed."""
import csv
import math
import os
import statistics
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "..", "scripts", "limit_table.py")
BIN = sys.argv.pop(1) if len(sys.argv) > 1 else os.path.join(HERE, "..", "build", "bin")


def run(args, out_dir):
    env = dict(os.environ, OCC_BIN=BIN, LP_NUM_THREADS="0")
    return subprocess.run([sys.executable, SCRIPT, *args, "--out", out_dir], env=env, capture_output=True, text=True,
                          timeout=600)


class LimitTable(unittest.TestCase):
    def assertRatio(self, ratio, a, b):
        """ratio (rounded to 0.01) is a / b of the unrounded medians that a and b round (to 0.01)."""
        lo, hi = (a - 0.005) / (b + 0.005), (a + 0.005) / max(b - 0.005, 1e-9)
        self.assertTrue(lo - 0.005 <= ratio <= hi + 0.005, f"{ratio} is not {a} / {b}")

    def test_one_view_end_to_end(self):
        with tempfile.TemporaryDirectory() as tmp:
            p = run(["--scene", "office", "--path", "walk:12", "--sizes", "96", "--repeats", "1", "--skip", "2"], tmp)
            self.assertEqual(p.returncode, 0, p.stdout[-2000:] + p.stderr[-2000:])
            with open(os.path.join(tmp, "limit.csv")) as f:
                rows = list(csv.DictReader(f))
            self.assertEqual(len(rows), 1)
            r = {k: (v if k in ("scene", "path") else float(v)) for k, v in rows[0].items()}
            for k in ("oracle", "none", "frustum", "cluster"):
                self.assertGreater(r[f"{k}_median_ms"], 0, k)
                self.assertGreaterEqual(r[f"{k}_p99_ms"], r[f"{k}_median_ms"] - 0.01, k)
            self.assertRatio(r["cluster_over_oracle"], r["cluster_median_ms"], r["oracle_median_ms"])
            best = min(r["none_median_ms"], r["frustum_median_ms"])
            self.assertRatio(r["cluster_over_best_single"], r["cluster_median_ms"], best)
            self.assertEqual(r["wrong_pixels"], 0)
            self.assertGreaterEqual(r["box_floor"], 1.0)
            self.assertGreater(r["occlusion_frames_pct"], 0)
            self.assertFalse(math.isnan(r["pvs_over_exact"]))
            self.assertGreaterEqual(r["pvs_over_exact"], 1.0)
            with open(os.path.join(tmp, "limit.md")) as f:
                table = f.read().splitlines()
            self.assertEqual(len(table), 3)
            self.assertIn("box floor", table[0])
            self.assertEqual(table[0].count("|"), table[2].count("|"))
            self.assertIn("office walk:12", table[2])

    def test_a_path_for_every_scene(self):
        with tempfile.TemporaryDirectory() as tmp:
            p = run(["--scene", "office", "--scene", "pipes", "--path", "walk:12"], tmp)
            self.assertNotEqual(p.returncode, 0)
            self.assertIn("limit_table: error: 2 --scene but 1 --path", p.stderr)
            self.assertEqual(os.listdir(tmp), [])

    def test_host_cpus(self):
        """--host-cpus: a bad value is one error before anything runs; with root and a cgroup CPU
        controller the timed runs go through CPU groups (the cluster's log says so), the
        single-process renders' figures are their CPU time over the cores, and no group is left
        behind."""
        with tempfile.TemporaryDirectory() as tmp:
            p = run(["--scene", "office", "--path", "walk:12", "--host-cpus", "lots"], tmp)
            self.assertNotEqual(p.returncode, 0)
            self.assertIn("limit_table: error: --host-cpus 'lots': expected a number of cores", p.stderr)
            self.assertEqual(os.listdir(tmp), [])
        root = "/sys/fs/cgroup/cpu" if os.path.exists("/sys/fs/cgroup/cpu/cpu.cfs_quota_us") else None
        if os.geteuid() != 0 or root is None:
            self.skipTest("needs root and cgroup v1's cpu hierarchy")
        with tempfile.TemporaryDirectory() as tmp:
            p = run(["--scene", "office", "--path", "walk:8", "--sizes", "64", "--skip", "2", "--host-cpus", "0.5"], tmp)
            self.assertEqual(p.returncode, 0, p.stdout[-2000:] + p.stderr[-2000:])
            with open(os.path.join(tmp, "0_64", "r0", "cluster.log")) as f:
                self.assertIn("each in a CPU group of 0.5 cores (--host-cpus)", f.read())
            # The single-process frames are timed by their CPU time over the group's 0.5 cores.
            with open(os.path.join(tmp, "limit.csv")) as f:
                row = next(csv.DictReader(f))
            for name, stats, col in (("oracle", "none", "oracle_cpu_ms"), ("none", "none", "cpu_ms"),
                                     ("frustum", "frustum", "cpu_ms")):
                with open(os.path.join(tmp, "0_64", "r0", stats, "stats.csv")) as f:
                    cpu = [float(r[col]) for r in list(csv.DictReader(f))[2:]]
                self.assertAlmostEqual(float(row[f"{name}_median_ms"]), statistics.median(cpu) / 0.5, delta=0.006,
                                       msg=name)
            self.assertEqual([g for g in os.listdir(root) if g.startswith("occswitch-")], [])


if __name__ == "__main__":
    unittest.main()
