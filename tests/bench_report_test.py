#!/usr/bin/env python3
"""scripts/bench_report.py's arithmetic on hand-made stats.csv files (signs, ratios,
wrong pixels, CPU columns and the three-machine model). Run by ctest (BenchReport.Arithmetic)."""
import csv
import importlib.util
import os
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
spec = importlib.util.spec_from_file_location("bench_report", os.path.join(HERE, "..", "scripts", "bench_report.py"))
report = importlib.util.module_from_spec(spec)
spec.loader.exec_module(report)

REF_COLS = ["frame", "nodes_drawn", "triangles_drawn", "render_ms", "queries", "cpu_ms"]
CLUSTER_COLS = ["frame", "camera", "hc_node", "visible", "added", "removed", "queries", "triangles", "bytes_received",
                "hc_ms", "or_ms", "rvg_ms", "latency_ms", "frame_interval_ms", "hc_cpu_ms", "or_cpu_ms",
                "or_tail_cpu_ms", "rvg_cpu_ms", "rvg_frame_cpu_ms", "full_set_bytes"]


def write(path, cols, rows):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(cols)
        for r in rows:
            w.writerow(r)


def cluster_row(f, interval, added, removed, bytes_, hc, orr, tail, rvg, visible=10, full_bytes=0):
    return [f, f, f % 2, visible, added, removed, 30, 1000, bytes_, 9.0, 2.0, 4.0, 20.0, interval, hc, orr, tail, 3.0, rvg,
            full_bytes]


class Fixture:
    """A bench OUT folder: 4 frames; none at 100 ms a frame (10 fps), CHC at 25 ms (40 fps) ..."""

    def __init__(self, inc_ids, full_ids):
        self.tmp = tempfile.TemporaryDirectory()
        out = self.out = self.tmp.name
        write(f"{out}/none/stats.csv", REF_COLS + ["exact_visible", "exact_triangles", "missed_visible"],
              [[f, 100, 5000, 100.0, 0, 90.0, 4, 400, 0] for f in range(4)])
        write(f"{out}/frustum/stats.csv", REF_COLS, [[f, 40, 2000, 50.0, 0, 45.0] for f in range(4)])
        write(f"{out}/stop-and-wait/stats.csv", REF_COLS, [[f, 5, 500, 200.0, 50, 150.0] for f in range(4)])
        write(f"{out}/chc/stats.csv", REF_COLS, [[f, 8, 800, 25.0, 20, 20.0] for f in range(4)])
        # GigaWalk: frame_ms 20 (50 fps); server OR 6 + HC 1, RVG 5 (ms columns).
        write(f"{out}/gigawalk/stats.csv", CLUSTER_COLS,
              [cluster_row(f, 20.0, 1, 1, 300, 1.0, 6.0, 0.0, 5.0) for f in range(4)])
        # Switch: frame_ms 12.5 (80 fps); ids per frame inc_ids (incremental) against the whole set's
        # full_ids (its visible count), 400 B against the 800 B the whole sets would take.
        write(f"{out}/switch/stats.csv", CLUSTER_COLS,
              [cluster_row(f, 12.5, inc_ids, 0, 400, 8.0, 4.0, 1.0 + f, 6.0, visible=full_ids, full_bytes=800)
               for f in range(4)])
        # frame_diff's output against brute force (per frame lines, then the summary line)
        for m, text in (("frustum", "frames=4 differing_pixels=0 max_frame_fraction=0\n"),
                        ("stop-and-wait", "frame 00001: 3 differing pixels (0.0025%)\n"
                                          "frames=4 differing_pixels=3 max_frame_fraction=2.5e-05\n"),
                        ("chc", "frames=4 differing_pixels=7 max_frame_fraction=5e-05\n"),
                        ("gigawalk", "frames=4 differing_pixels=0 max_frame_fraction=0\n"),
                        ("switch", "frames=4 differing_pixels=2 max_frame_fraction=1e-05\n")):
            with open(f"{out}/{m}/wrong.txt", "w") as fh:
                fh.write(text)

    def run(self, *extra):
        report.main([self.out, "scene", "walk:4", "40", "30", *extra])
        with open(f"{self.out}/bench.csv") as f:
            rows = {r["method"]: r for r in csv.DictReader(f)}
        with open(f"{self.out}/bench.md") as f:
            md = f.read()
        return rows, md


class ChangeInWords(unittest.TestCase):
    def test_fewer_more_and_equal(self):
        self.assertEqual(report.change(48.0, 100.0, "ids"), "52 % fewer ids")
        self.assertEqual(report.change(45.7, 26.9, "ids"), "70 % more ids")  # the case: incremental sent more
        self.assertEqual(report.change(10.0, 10.0, "ids"), "as many ids")
        self.assertEqual(report.change(0.0, 0.0, "ids"), "as many ids")


class Report(unittest.TestCase):
    def test_ratios_wrong_pixels_and_cpu_columns(self):
        fx = Fixture(inc_ids=5, full_ids=20)
        self.addCleanup(fx.tmp.cleanup)
        rows, md = fx.run()
        self.assertEqual(list(rows), ["none", "frustum", "stop-and-wait", "chc", "gigawalk", "switch"])
        self.assertEqual(rows["none"]["mean_fps"], "10.00")
        self.assertEqual(rows["chc"]["mean_fps"], "40.00")
        self.assertEqual(rows["chc"]["fps_ratio_to_none"], "4.00")           # 40 fps / 10 fps
        self.assertEqual(rows["stop-and-wait"]["fps_ratio_to_none"], "0.50")  # slower than none: below 1
        self.assertEqual(rows["chc"]["fps_ratio_to_gigawalk"], "0.80")        # 40 / 50
        self.assertEqual(rows["switch"]["fps_ratio_to_gigawalk"], "1.60")     # 80 / 50
        self.assertEqual(rows["chc"]["pvs_exact_ratio"], "2.00")              # 8 drawn / 4 exactly visible
        self.assertEqual(rows["none"]["wrong_pixels"], "0")
        self.assertEqual(rows["stop-and-wait"]["wrong_pixels"], "3")
        self.assertEqual(rows["stop-and-wait"]["worst_frame_wrong_fraction"], "0.000025")
        self.assertEqual(rows["chc"]["wrong_pixels"], "7")
        self.assertEqual(rows["switch"]["wrong_pixels"], "2")
        self.assertEqual(rows["chc"]["cpu_ms_per_frame"], "20.00")
        self.assertEqual(rows["chc"]["model_ms_three_machines"], "20.00")     # one process: its CPU time
        self.assertEqual(rows["switch"]["cpu_ms_per_frame_hc"], "8.00")
        self.assertEqual(rows["switch"]["cpu_ms_per_frame_or"], "4.00")
        self.assertEqual(rows["switch"]["cpu_ms_per_frame_or_tail"], "2.50")  # mean of 1, 2, 3, 4
        self.assertEqual(rows["switch"]["cpu_ms_per_frame_rvg"], "6.00")
        self.assertEqual(rows["switch"]["cpu_ms_per_frame"], "18.00")         # HC + OR + RVG
        self.assertEqual(rows["gigawalk"]["cpu_ms_per_frame"], "12.00")       # 1 + 6 + 5
        self.assertEqual(rows["switch"]["bytes_per_frame"], "400")
        for col in ("wrong_pixels", "worst_frame_wrong_fraction", "cpu_ms_per_frame_hc", "cpu_ms_per_frame_or",
                    "cpu_ms_per_frame_rvg", "model_ms_three_machines"):
            self.assertIn(col, rows["switch"])
        self.assertIn("75 % fewer ids, 50 % fewer bytes", md)               # 5 vs 20 ids, 400 vs 800 B

    def test_incremental_that_sends_more_says_more(self):
        fx = Fixture(inc_ids=30, full_ids=20)
        self.addCleanup(fx.tmp.cleanup)
        rows, md = fx.run()
        self.assertIn("30.0 ids/frame (400 B/frame) vs full sets 20.0 ids/frame (800 B/frame): 50 % more ids, "
                      "50 % fewer bytes", md)

    def test_three_machine_model(self):
        fx = Fixture(inc_ids=5, full_ids=20)
        self.addCleanup(fx.tmp.cleanup)
        rows, _ = fx.run()
        # Per frame: max(HC + D + bytes/G + OR_tail(f+1), (HC + OR)/2, RVG, (D + OR - OR_tail)/(L-1)), D = 0:
        # f0: 8 + 0.0032 + 2 = 10.0032; f1: 8 + 0.0032 + 3; f2: 8 + 0.0032 + 4; f3 (no next frame): max(6, 6, 0) = 6
        t = 400 * 8 / 1e9 * 1e3
        expect = ((10 + t) + (11 + t) + (12 + t) + 6) / 4
        self.assertAlmostEqual(float(rows["switch"]["model_ms_three_machines"]), expect, places=2)
        # GigaWalk: max(server 1 + 6 + bytes, RVG 5) = 7.0024
        self.assertAlmostEqual(float(rows["gigawalk"]["model_ms_three_machines"]), 7.0, places=2)
        # A link delay (--model-delay-ms 5) lands on the switch's chain of HCs once per frame.
        rows5, md5 = fx.run("--model-delay-ms", "5")
        self.assertAlmostEqual(float(rows5["switch"]["model_ms_three_machines"]),
                               ((15 + t) + (16 + t) + (17 + t) + max(6, (5 + 4 - 4) / 2)) / 4, places=2)
        self.assertIn("5 ms link delay", md5)


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0]] + sys.argv[1:])
