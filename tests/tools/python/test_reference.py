"""The Python module answers exactly as the C++ API does on the same points.

ccmap_py_reference (ccmap_py_reference.cpp, C++ only, no code of tools/python) feeds fixed
frames to Stack<Config> for each of the four presets and prints every input and answer with
floats as bit patterns. This test replays the inputs through ccmap.Map, in several array layouts
(float32 views, float64 copies, strided float32), and compares every answer bitwise: frame
counters, refusals, stack and per-layer queries (query and query_many), every layer's export
(layer and layer_grid), window centres, cell widths, thresholds, totals. It then loads the C++
snapshot with Map.load and compares it with the replayed map, and compares the replayed map's
own snapshot with the C++ one byte for byte.
"""
import math
import os
import subprocess
import tempfile
import unittest

import numpy as np

import ccmap
from support import bits, f32_from_bits, main

REFERENCE = os.environ.get("CCMAP_PY_REFERENCE", "")
SCENARIOS = ("cadre_stereo", "cadre_upset", "ccm_lidar", "kf_stereo", "omg_inverse_variance")
QUERY_FLOATS = ("slope_x", "slope_y", "inclination", "normal_variance_m2", "elevation_variance_m2", "weight")
CELL_FLOATS = ("cx", "cy", "weight", "height", "slope_x", "slope_y", "normal_var", "elev_var")


def parse_transcript(text):
    """{scenario: (preset, kwargs, [operation, ...])}; an operation is a (kind, data) tuple."""
    lines = text.splitlines()
    scenarios, i = {}, 0
    ops = None
    while i < len(lines):
        tokens = lines[i].split()
        i += 1
        kind = tokens[0]
        if kind == "map":
            kwargs = {}
            for item in tokens[3:]:
                key, value = item.split("=", 1)
                if value.startswith("@"):
                    kwargs[key] = value[1:]
                elif value.startswith("["):
                    kwargs[key] = [float(f32_from_bits(v)) for v in value[1:-1].split(",")]
                else:
                    kwargs[key] = float(f32_from_bits(value))
            ops = []
            scenarios[tokens[1]] = (tokens[2], kwargs, ops)
        elif kind == "points":
            n, with_weights = int(tokens[1]), tokens[2] == "1"
            raw = np.array([[int(v, 16) for v in line.split()] for line in lines[i:i + n]], dtype=np.uint32)
            raw = raw.reshape(n, 4 if with_weights else 3)
            values = raw.view(np.float32)
            ops.append(("points", (values[:, :3].copy(), values[:, 3].copy() if with_weights else None)))
            i += n
        elif kind == "layer":
            count = int(tokens[2])
            rows = [line.split() for line in lines[i:i + count]]
            i += count
            ops.append(("layer", (int(tokens[1]), int(tokens[3]), (int(tokens[4]), int(tokens[5])),
                                  tokens[6], tokens[7], rows)))
        elif kind == "end":
            ops = None
        else:
            ops.append((kind, tokens[1:]))
    return scenarios


def counters(tokens):
    return {k: int(v) for k, v in (t.split("=") for t in tokens)}


def as_layout(points, layout):
    """The same float32 values as a C-contiguous float32 array (handed over without a copy),
    a float64 array, or a strided float32 view (copied by the module)."""
    if layout == 0:
        return np.ascontiguousarray(points)
    if layout == 1:
        return points.astype(np.float64)
    wide = np.zeros((len(points), 5), dtype=np.float32)
    wide[:, 1:4] = points
    return wide[:, 1:4]


class ReferenceTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        if not REFERENCE:
            raise unittest.SkipTest("CCMAP_PY_REFERENCE (the ccmap_py_reference program) is not set")
        cls.tmp = tempfile.TemporaryDirectory()
        text = subprocess.run([REFERENCE, cls.tmp.name], check=True, capture_output=True, text=True).stdout
        cls.scenarios = parse_transcript(text)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def test_transcript_covers_every_preset(self):
        self.assertEqual(set(self.scenarios), set(SCENARIOS))
        self.assertEqual({preset for preset, _, _ in self.scenarios.values()}, set(ccmap.PRESETS))

    # ---- comparisons ----
    def check_query(self, got, expected, where):
        """got: the module's dict (or a structured row); expected: the C++ QueryResult fields."""
        status, layer = expected["status"], int(expected["layer"])
        self.assertEqual(got["status"], status, where)
        self.assertEqual(int(got["layer"]), layer, where)
        self.assertEqual(got["class"], expected["class"], where)
        self.assertEqual(int(got["upset"]), int(expected["upset"]), f"{where}: upset")
        for key in QUERY_FLOATS:
            self.assertEqual(bits(got[key]), int(expected[key], 16), f"{where}: {key}")
        raw_height = f32_from_bits(expected["height_m"])
        if status == "ok":
            self.assertEqual(bits(got["height_m"]), int(expected["height_m"], 16), f"{where}: height_m")
            self.assertEqual(bits(got["cell_width_m"]), int(expected["cell_width_m"], 16), where)
        else:  # the CLI's rule: no height without an answer; the width of the layer named
            self.assertTrue(math.isnan(got["height_m"]), f"{where}: height_m {got['height_m']} for {status}")
            self.assertEqual(raw_height, 0.0, where)
        width = self.map.cell_widths[layer] if layer >= 0 else 0.0
        self.assertEqual(bits(got["cell_width_m"]), bits(width), f"{where}: cell_width_m")
        self.assertAlmostEqual(got["inclination_deg"], math.degrees(math.atan(got["inclination"])), places=12)

    def check_layer(self, m, data, where):
        k, side, centre, width, threshold, rows = data
        self.assertEqual(m.sides[k], side, where)
        self.assertEqual(m.window_centres[k], centre, where)
        self.assertEqual(bits(m.cell_widths[k]), int(width, 16), where)
        self.assertEqual(bits(m.normal_variance_thresholds[k]), int(threshold, 16), where)
        cells = m.layer(k)
        self.assertEqual(len(cells), len(rows), f"{where}: cells exported")
        if not rows:
            self.assertTrue(np.isnan(m.layer_grid(k, "height")).all(), where)
            return
        table = np.array(rows)
        np.testing.assert_array_equal(cells["ix"], table[:, 0].astype(np.int64), where)
        np.testing.assert_array_equal(cells["iy"], table[:, 1].astype(np.int64), where)
        np.testing.assert_array_equal(cells["layer"], k)
        np.testing.assert_array_equal(cells["res"].view(np.uint32), int(width, 16))
        for column, name in enumerate(CELL_FLOATS, start=2):
            expected = np.array([int(v, 16) for v in table[:, column]], dtype=np.uint32)
            np.testing.assert_array_equal(cells[name].view(np.uint32), expected, f"{where}: {name}")
        np.testing.assert_array_equal(cells["class"], table[:, 10], f"{where}: class")
        # layer_grid: row = iy - lowest iy, column = ix - lowest ix; NaN exactly where unexported.
        grid = m.layer_grid(k, "height")
        self.assertEqual(grid.shape, (side, side))
        row = cells["iy"] - (centre[1] - side // 2)
        col = cells["ix"] - (centre[0] - side // 2)
        np.testing.assert_array_equal(grid[row, col].view(np.uint32), cells["height"].view(np.uint32), where)
        self.assertEqual(int(np.isnan(grid).sum()), side * side - len(rows), f"{where}: NaN cells")
        codes = m.layer_grid(k, "class")[row, col].astype(int)
        np.testing.assert_array_equal(np.array(ccmap.CLASS_NAMES)[codes], cells["class"], where)

    # ---- replay ----
    def replay(self, name):
        preset, kwargs, ops = self.scenarios[name]
        m = self.map = ccmap.Map(preset, **kwargs)
        points = weights = None
        frames = 0
        upset_loaded = False
        stack_queries, layer_queries = [], {}
        for kind, data in ops:
            where = f"{name}: {kind} {' '.join(data[:3]) if isinstance(data, list) else ''}"
            if kind == "points":
                points, weights = data
            elif kind == "move":
                x, y = (float(f32_from_bits(v)) for v in data[:2])
                if data[2] == "ok":
                    m.move_to(x, y)
                else:
                    with self.assertRaises(ccmap.StatusError) as refusal:
                        m.move_to(x, y)
                    self.assertEqual(refusal.exception.status, data[2], where)
            elif kind in ("frame", "sensor_frame"):
                floats = 3 if kind == "frame" else 12
                values = [float(f32_from_bits(v)) for v in data[:floats]]
                status, expected = data[floats], counters(data[floats + 1:])
                layout = as_layout(points, frames % 3)  # accepted frames cycle through the layouts
                frames += status == "ok"
                if kind == "frame":
                    call = lambda: m.update(layout, values, weights)  # noqa: E731
                else:
                    rotation = np.array(values[:9], dtype=np.float32).reshape(3, 3)
                    call = lambda: m.update_sensor(layout, rotation, values[9:])  # noqa: E731
                if status == "ok":
                    self.assertEqual(call(), expected, where)
                else:
                    with self.assertRaises(ccmap.StatusError) as refusal:
                        call()
                    self.assertEqual(refusal.exception.status, status, where)
            elif kind == "query":
                layer = int(data[0])
                x, y = (f32_from_bits(v) for v in data[1:3])
                expected = dict(t.split("=") for t in data[3:])
                got = m.query(float(x), float(y), layer=None if layer < 0 else layer)
                self.check_query(got, expected, f"{name}: query layer {layer} at ({x}, {y})")
                (stack_queries if layer < 0 else layer_queries.setdefault(layer, [])).append((x, y, expected))
            elif kind == "layer":
                self.check_layer(m, data, f"{name}: layer {data[0]}")
            elif kind == "totals":
                self.assertEqual(m.total_counters, counters(data), f"{name}: totals")
            elif kind == "rejected":
                self.assertEqual((m.rejected_moves, m.rejected_frames), (int(data[0]), int(data[1])), name)
            elif kind == "upset":
                # Python cannot flip the bits: from here the map is the C++ one's snapshot, which
                # carries the distrusted cells (and the counters of the scrub that found them).
                self.assertGreater(int(data[0]), 0, where)
                m = self.map = ccmap.Map.load(next(d[0] for k, d in ops if k == "snapshot"), m.preset)
                upset_loaded = True
            elif kind == "snapshot":
                self.check_snapshot(m, data[0], ops, name)
            else:
                self.fail(f"unknown transcript line {kind}")
        self.assertGreater(frames, 1)
        self.assertGreater(len(stack_queries), 100)
        for layer, queries in [(None, stack_queries)] + sorted(layer_queries.items()):
            xy = np.array([(x, y) for x, y, _ in queries], dtype=np.float32)
            rows = m.query_many(xy, layer=layer)
            self.assertEqual(len(rows), len(queries))
            for row, (x, y, expected) in zip(rows, queries):
                self.check_query(row, expected, f"{name}: query_many layer {layer} at ({x}, {y})")
        self.assertIn("ok", {e["status"] for _, _, e in stack_queries}, "some query must be answered")
        upset_answers = [e for _, _, e in stack_queries if e["upset"] == "1"]
        self.assertEqual(bool(upset_answers), upset_loaded, f"{name}: upset answers only after upsets")
        self.assertTrue(all(e["status"] == "unknown" for e in upset_answers), f"{name}: an upset answers unknown")

    def check_snapshot(self, m, path, ops, name):
        with open(path, "rb") as f:
            cxx = f.read()
        ours = m.snapshot()
        self.assertEqual(len(ours), ccmap.snapshot_size(m.preset))
        self.assertEqual(ours, cxx, f"{name}: snapshot bytes")
        loaded = ccmap.Map.load(path)  # the preset is found by trying the four
        self.assertEqual(loaded.preset, m.preset)
        for kind, data in ops:
            if kind == "layer":
                self.check_layer(loaded, data, f"{name}: layer {data[0]} of the loaded C++ snapshot")
        self.assertEqual(loaded.total_counters, m.total_counters)


for _name in SCENARIOS:
    setattr(ReferenceTest, f"test_{_name}", lambda self, n=_name: self.replay(n))

if __name__ == "__main__":
    raise SystemExit(main())
