"""examples/python/map_laser_scan.py runs on the real laser scan and writes a PNG (skipped,
saying why, without the shared data set)."""
import os
import re
import subprocess
import sys
import tempfile
import unittest

from support import main

SOURCE_DIR = os.environ.get("CCMAP_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", "..", ".."))
EXAMPLE = os.path.join(SOURCE_DIR, "examples", "python", "map_laser_scan.py")
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


class Example(unittest.TestCase):
    def run_example(self, *args):
        return subprocess.run([sys.executable, EXAMPLE, "--skip-code", *args], capture_output=True, text=True)

    def test_maps_the_crop_and_writes_a_png(self):
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "scan.png")
            run = self.run_example("--out", out)
            if run.returncode == 77:
                self.skipTest(run.stdout.strip())
            self.assertEqual(run.returncode, 0, run.stdout + run.stderr)
            # Every point of the crop lands in the 41 m window: folded in, or judged by the outlier
            # gate (steam and vegetation returns; docs/design.md "Outlier gate and change").
            counts = dict(re.findall(r"(\w+) (\d+)", run.stdout.split("frame counters:")[1].splitlines()[0]))
            self.assertEqual(int(counts["received"]), 53810)
            judged = sum(int(counts.get(k, 0)) for k in ("gated_finer", "gated_occluded", "gated_held", "gated_pool_full"))
            self.assertEqual(int(counts["used"]) + judged, 53810)
            with open(out, "rb") as f:
                self.assertEqual(f.read(8), PNG_SIGNATURE)
            self.assertGreater(os.path.getsize(out), 20000)

    def test_without_data_it_says_why(self):
        run = self.run_example("--data", "/nonexistent")
        self.assertEqual(run.returncode, 77)
        self.assertIn("not available", run.stdout)
        run = subprocess.run([sys.executable, EXAMPLE, "--data", "/nonexistent"], capture_output=True, text=True)
        self.assertEqual(run.returncode, 0)  # a user without the data is told, not failed


if __name__ == "__main__":
    raise SystemExit(main())
