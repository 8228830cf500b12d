"""ccmap.read_global_map (tools/global_map, docs/design.md section 13): the global map of a patch
directory. The patches are written here, byte by byte from the format of
include/ccmap/global/patch_keeper.hpp (an encoder independent of the library's), holding the
exact moments of points on a known plane as a rover whose odometry was off saw them; their
corrected poses say where they belong. Reference: the plane itself at every pixel centre."""
import math
import os
import struct
import tempfile
import unittest
import zlib

import numpy as np

import ccmap
from support import main

W = 0.08   # cell width (m)
T = 16     # tile side (cells)


def plane(x, y):
    return 0.1 * x - 0.05 * y + 0.2


def motion(written, corrected):
    """M = C W^-1 as (c, s, tx, ty): m' = R m + t."""
    turn = corrected[2] - written[2]
    c, s = math.cos(turn), math.sin(turn)
    return c, s, corrected[0] - (c * written[0] - s * written[1]), corrected[1] - (s * written[0] + c * written[1])


def cell_bytes(ix, iy, m):
    """The moments of a 4 x 4 lattice of points in cell (ix, iy) of the written frame, their heights
    those of the plane where the motion m puts them (the ground they were seen on)."""
    c, s, tx, ty = m
    cx, cy = (ix + 0.5) * W, (iy + 0.5) * W
    pts = []
    for j in range(4):
        for i in range(4):
            x, y = ix * W + (i + 0.5) * W / 4, iy * W + (j + 0.5) * W / 4
            pts.append((x, y, plane(c * x - s * y + tx, s * x + c * y + ty)))
    p = np.array(pts)
    mean = p.mean(axis=0)
    d = p - mean
    n = float(len(pts))
    fields = [n, mean[0] - cx, mean[1] - cy, mean[2], (d[:, 0] ** 2).sum(), (d[:, 1] ** 2).sum(),
              (d[:, 2] ** 2).sum(), (d[:, 0] * d[:, 2]).sum(), (d[:, 1] * d[:, 2]).sum(), (d[:, 0] * d[:, 1]).sum()]
    return struct.pack("<10f", *fields)


def patch_file(directory, tile_x, tile_y, written, corrected):
    """Writes L0_<tx>_<ty>.ccp: format version 2, kind 3 (CCM full), every cell observed."""
    m = motion(written, corrected)
    cells = b"".join(cell_bytes(tile_x * T + i, tile_y * T + j, m) for j in range(T) for i in range(T))
    size = 64 + len(cells) + 4
    header = b"CCMP" + struct.pack("<HBBIiiif5fI3f", 2, 3, T, size, 0, tile_x, tile_y, W, written[0], written[1],
                                   written[2], 0.05, 0.01, 7, corrected[0], corrected[1], corrected[2])
    assert len(header) == 64
    body = header + cells
    path = os.path.join(directory, f"L0_{tile_x}_{tile_y}.ccp")
    with open(path, "wb") as f:
        f.write(body + struct.pack("<I", zlib.crc32(body)))
    return path


class GlobalMap(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = self.tmp.name
        # Two tiles the rover wrote at (3, 1, 0.2) while it was truly at (3.4, 0.7, 0.5).
        self.written = (3.0, 1.0, 0.2)
        self.corrected = (3.4, 0.7, 0.5)
        for tx in (1, 2):
            self.path = patch_file(self.dir, tx, 0, self.written, self.corrected)

    def tearDown(self):
        self.tmp.cleanup()

    def pixel_centres(self, g):
        ny, nx = g["height"].shape
        x = g["x_min"] + (np.arange(nx) + 0.5) * g["cell_width"]
        y = g["y_min"] + (np.arange(ny) + 0.5) * g["cell_width"]
        return np.meshgrid(x, y)

    def test_the_corrected_map_is_the_plane_where_the_patches_belong(self):
        g = ccmap.read_global_map(self.dir)
        self.assertEqual(g["patches"], 2)
        self.assertEqual(g["refused"], [])
        self.assertAlmostEqual(g["cell_width"], W, places=6)
        x, y = self.pixel_centres(g)
        known = np.isfinite(g["height"])
        # The moved footprints tile the plane: one pixel per cell, give or take the borders.
        self.assertGreater(known.sum(), 2 * T * T - 4 * T)
        self.assertLess(known.sum(), 2 * T * T + 4 * T)
        err = np.abs(g["height"][known] - plane(x[known], y[known]))
        self.assertLess(err.max(), 2e-5)
        # Slopes: the plane's gradient in the map frame.
        self.assertLess(np.abs(g["slope_x"][known] - 0.1).max(), 1e-4)
        self.assertLess(np.abs(g["slope_y"][known] + 0.05).max(), 1e-4)
        self.assertTrue(np.all(g["weight"][known] >= 16.0))
        self.assertTrue(np.all(g["cell_class"][known] == 1.0))  # traversable
        self.assertEqual(g["hazard_pixels"], 0)
        # Where the cells belong: the tiles' footprint moved by C W^-1.
        c, s, tx, ty = motion(self.written, self.corrected)
        u = c * (x[known] - tx) + s * (y[known] - ty)  # back into the written frame
        v = -s * (x[known] - tx) + c * (y[known] - ty)
        self.assertTrue(np.all((u >= T * W - 1e-6) & (u <= 3 * T * W + 1e-6) & (v >= -1e-6) & (v <= T * W + 1e-6)))

    def test_uncorrected_the_patches_lie_where_odometry_put_them(self):
        g = ccmap.read_global_map(self.dir, corrected=False)
        x, y = self.pixel_centres(g)
        known = np.isfinite(g["height"])
        self.assertGreater(known.sum(), 2 * T * T - 4 * T)
        # Each cell's own plane (the heights it was seen with) at the written place: off the map plane.
        err = np.abs(g["height"][known] - plane(x[known], y[known]))
        self.assertGreater(np.median(err), 0.02)
        self.assertGreaterEqual(x[known].min(), T * W - W)
        self.assertLessEqual(x[known].max(), 3 * T * W + W)

    def test_a_damaged_file_is_named_and_skipped(self):
        with open(self.path, "r+b") as f:
            f.seek(500)
            b = f.read(1)
            f.seek(500)
            f.write(bytes([b[0] ^ 0x08]))
        g = ccmap.read_global_map(self.dir)
        self.assertEqual(g["patches"], 1)
        self.assertEqual(g["refused"], [os.path.basename(self.path)])
        with self.assertRaises(ccmap.StatusError):
            ccmap.read_global_map(os.path.join(self.dir, "missing"))
        with self.assertRaises(ccmap.StatusError):
            ccmap.read_global_map(self.dir, layer=9)


if __name__ == "__main__":
    raise SystemExit(main())
