"""examples/python/map_laser_scan.py runs on the real laser scan and writes a PNG (skipped,
saying why, without the shared data set)."""
import os
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
            self.assertIn("used 53810", run.stdout)  # every point of the crop lands in the 41 m window
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
