"""The Python module's own contract (docs/python.md): construction and parameters, every refusal
(leaving the map unchanged), bad values inside well-formed arrays counted and skipped exactly as
the C++ library does, save/load round trips, layer_grid orientation and NaN where unobserved.
Bitwise agreement with the C++ API is test_reference.py's job."""
import math
import os
import re
import tempfile
import unittest

import numpy as np

import ccmap
from support import bits, main

SOURCE_DIR = os.environ.get("CCMAP_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", "..", ".."))
# The keys `ccmap query` prints (tools/cli/cli.cpp, run_query), in its order.
CLI_QUERY_KEYS = ["x", "y", "status", "layer", "cell_width_m", "height_m", "slope_x", "slope_y", "inclination",
                  "inclination_deg", "normal_variance_m2", "elevation_variance_m2", "weight", "class", "upset"]


def ground(n, seed, x=(0.3, 2.5), y=(-1.2, 1.2)):
    """n points on a plane z = 0.05 x - 0.02 y with 1 mm noise, float64, map frame."""
    rng = np.random.default_rng(seed)
    px = rng.uniform(*x, n)
    py = rng.uniform(*y, n)
    return np.column_stack([px, py, 0.05 * px - 0.02 * py + 0.001 * rng.standard_normal(n)])


SENSOR = (0.0, 0.0, 0.175)


def state(m):
    """Everything a refusal must leave alone: cells of every layer, windows, life-time counters."""
    return ([m.layer(k).tobytes() for k in range(m.layer_count)], m.window_centres, m.total_counters)


class Construction(unittest.TestCase):
    def test_presets_have_the_library_shapes(self):
        shapes = {"cadre": [64, 64, 64, 32, 32], "ccm": [256], "kf": [256], "omg": [256]}
        finest = {"cadre": np.float32(0.04), "ccm": np.float32(0.08), "kf": np.float32(0.08), "omg": np.float32(0.08)}
        self.assertEqual(ccmap.PRESETS, ("cadre", "ccm", "kf", "omg"))
        for preset in ccmap.PRESETS:
            m = ccmap.Map(preset)
            self.assertEqual(m.preset, preset)
            self.assertEqual(m.sides, shapes[preset])
            self.assertEqual(m.layer_count, len(shapes[preset]))
            expected = [finest[preset] * np.float32(2 ** k) for k in range(m.layer_count)]
            np.testing.assert_array_equal(bits(m.cell_widths), bits(expected))
            self.assertEqual(m.window_centres, [(0, 0)] * m.layer_count)
            self.assertEqual(m.total_counters, dict.fromkeys(m.total_counters, 0))
        self.assertEqual(ccmap.Map().preset, "cadre")
        self.assertEqual(ccmap.Map().layer_is_ccm, [False, True, True, True, True])

    def test_cell_width_and_parameters_by_name(self):
        m = ccmap.Map("ccm", cell_width=0.16)
        self.assertEqual(bits(m.cell_widths[0]), bits(np.float32(0.16)))
        values = {"weight_limit": 50.0, "coverage_tau": 0.7, "min_weight": 2.0, "obstacle_fraction": 0.5,
                  "max_inclination": 0.5, "kalman_min_variance": 1e-6, "finest_max_sigma_m": 0.004}
        m = ccmap.Map("cadre", **values)
        for key, value in values.items():
            self.assertEqual(bits(m.params[key]), bits(np.float32(value)), key)
        m = ccmap.Map("ccm", normal_variance_threshold=[0.001])
        self.assertEqual(bits(m.normal_variance_thresholds[0]), bits(np.float32(0.001)))
        calibrated = ccmap.Map("ccm").normal_variance_thresholds[0]
        self.assertGreater(calibrated, 0.0)
        self.assertNotEqual(calibrated, m.normal_variance_thresholds[0])

    def test_frame_budget_by_name(self):
        m = ccmap.Map("cadre", frame_point_budget=1000, frame_time_budget_us=0)
        self.assertEqual(m.params["frame_point_budget"], 1000)
        pts = np.array([[0.5 + 0.001 * i, 0.0, 0.0] for i in range(3000)], dtype=np.float32)
        counts = m.update(pts, SENSOR)
        # Whole chunks of 256 points, in bit-reversed order of 16, while the next one fits: chunks
        # 0, 8 and 4 (768 points); the fourth (chunk 2) would exceed 1000.
        self.assertEqual(counts["skipped_budget"], 3000 - 768)
        self.assertEqual(counts["received"], 3000)
        with self.assertRaises(TypeError):
            ccmap.Map("cadre", frame_point_budget=1.5)
        with self.assertRaises(ValueError):
            ccmap.Map("cadre", frame_time_budget_us=-1)

    def test_sensor_choice(self):
        self.assertEqual(ccmap.Map().params["sensor"], "stereo")
        self.assertAlmostEqual(ccmap.Map().params["stereo_sigma_per_range_sq"], 1 / 300, places=9)  # CADRE
        m = ccmap.Map("ccm", sensor="lidar", lidar_sigma_m=0.01, lidar_sigma_per_m=0.001)
        self.assertEqual(m.params["sensor"], "lidar")
        self.assertEqual(bits(m.params["lidar_sigma_m"]), bits(np.float32(0.01)))
        self.assertEqual(bits(m.params["lidar_sigma_per_m"]), bits(np.float32(0.001)))
        m = ccmap.Map("omg", focal_px=800, baseline_m=0.1, disparity_sigma_px=0.2, weight_mode="inverse_variance",
                      reference_range_m=1.5)
        self.assertAlmostEqual(m.params["stereo_sigma_per_range_sq"], 0.2 / 80, places=9)
        self.assertEqual(m.params["weight_mode"], "inverse_variance")
        # Far points weigh less with inverse-variance weights: the mean follows the near points.
        near = m.update(ground(10, 1, x=(0.5, 0.6)), SENSOR)
        self.assertEqual(near["used"], 10)

    def test_unknown_keyword_is_a_type_error_naming_it(self):
        with self.assertRaisesRegex(TypeError, "'wieght_limit'"):
            ccmap.Map("cadre", wieght_limit=5.0)
        with self.assertRaisesRegex(TypeError, "lidar_sigma_m"):
            ccmap.Map("cadre", lidar_sigma_m=0.01)  # the default sensor is stereo
        with self.assertRaisesRegex(TypeError, "focal_px"):
            ccmap.Map("cadre", sensor="lidar", focal_px=600)
        for bad in ("1.0", True, None, [1.0]):
            with self.assertRaises(TypeError, msg=repr(bad)):
                ccmap.Map("cadre", weight_limit=bad)

    def test_bad_preset_and_refused_parameters_raise_status_errors(self):
        cases = [
            ({"preset": "kalman"}, "invalid_argument"),
            ({"weight_limit": -1.0}, "invalid_argument"),
            ({"weight_limit": 1e-4}, "invalid_argument"),  # below kMinWeightLimit
            ({"coverage_tau": float("nan")}, "non_finite_input"),
            ({"cell_width": 0.0}, "invalid_argument"),
            ({"cell_width": float("inf")}, "non_finite_input"),
            ({"sensor": "lidar", "lidar_sigma_m": -0.01}, "invalid_argument"),
            ({"sensor": "sonar"}, "invalid_argument"),
            ({"weight_mode": "square"}, "invalid_argument"),
            ({"normal_variance_threshold": [0.0] * 9}, "invalid_argument"),
        ]
        for kwargs, status in cases:
            with self.assertRaises(ccmap.StatusError, msg=repr(kwargs)) as refusal:
                ccmap.Map(**kwargs)
            self.assertEqual(refusal.exception.status, status, repr(kwargs))
            self.assertTrue(str(refusal.exception).startswith(status + ":"), str(refusal.exception))
            self.assertIsInstance(refusal.exception, ValueError)
        with self.assertRaisesRegex(ValueError, "kalman.*cadre, ccm, kf, omg"):
            ccmap.Map("kalman")


class Refusals(unittest.TestCase):
    """Every refusal raises StatusError and leaves the map as it was. Bad arrays are refused
    before the library sees them (its rejected-frame counter does not move); bad origins and
    poses are the library's refusals (it counts them)."""

    def setUp(self):
        self.m = ccmap.Map("cadre")
        self.m.update(ground(3000, 1), SENSOR)
        self.points = ground(200, 2)

    def refused(self, status, call, counted_by_library):
        before = state(self.m)
        frames, moves = self.m.rejected_frames, self.m.rejected_moves
        with self.assertRaises(ccmap.StatusError) as refusal:
            call()
        self.assertEqual(refusal.exception.status, status)
        self.assertEqual(state(self.m), before, "a refusal changed the map")
        self.assertEqual(self.m.rejected_frames + self.m.rejected_moves - frames - moves, int(counted_by_library))

    def test_points_of_the_wrong_shape_or_dtype(self):
        p = self.points
        bad_points = [p[:, :2], np.column_stack([p, p[:, :1]]), p[0], p[:, :, None], p.T, np.zeros((0,)),
                      p.astype(np.int64), p.astype(np.float16), p.astype(np.complex64), p > 0, p.astype(object),
                      p.astype(">f4"), [["a", "b", "c"]], None, "points", 3.0]
        for bad in bad_points:
            with self.subTest(points=getattr(bad, "dtype", type(bad)), shape=getattr(bad, "shape", None)):
                self.refused("invalid_argument", lambda: self.m.update(bad, SENSOR), False)
                self.refused("invalid_argument", lambda: self.m.update_sensor(bad, np.eye(3), SENSOR), False)

    def test_weights_of_the_wrong_shape_or_dtype(self):
        n = len(self.points)
        for bad in (np.ones(n - 1), np.ones((n, 1)), np.ones(n, dtype=np.int32), np.ones(n, dtype=bool), "1"):
            with self.subTest(weights=getattr(bad, "shape", bad)):
                self.refused("invalid_argument", lambda: self.m.update(self.points, SENSOR, bad), False)

    def test_bad_sensor_origin(self):
        for bad, status, counted in [((np.nan, 0, 0.175), "non_finite_input", True),
                                     ((0, np.inf, 0.175), "non_finite_input", True),
                                     ((2e5, 0, 0.175), "out_of_range", True),
                                     ((0, 0), "invalid_argument", False),
                                     ((0, 0, 0, 0), "invalid_argument", False),
                                     ("abc", "invalid_argument", False),
                                     (None, "invalid_argument", False)]:
            with self.subTest(origin=bad):
                self.refused(status, lambda: self.m.update(self.points, bad), counted)

    def test_bad_pose(self):
        rotation = np.eye(3)
        bad_rotation = rotation.copy()
        bad_rotation[1, 2] = np.nan
        cases = [(bad_rotation, SENSOR, "non_finite_input", True),
                 (rotation, (0, np.nan, 0), "non_finite_input", True),
                 (rotation[:2], SENSOR, "invalid_argument", False),
                 (rotation.ravel(), SENSOR, "invalid_argument", False),
                 (rotation, (0, 0), "invalid_argument", False)]
        for r, t, status, counted in cases:
            with self.subTest(rotation=r.shape, translation=t):
                self.refused(status, lambda: self.m.update_sensor(self.points, r, t), counted)

    def test_bad_moves(self):
        self.refused("non_finite_input", lambda: self.m.move_to(float("nan"), 0.0), True)
        self.refused("out_of_range", lambda: self.m.move_to(0.0, 1e6), True)
        with self.assertRaises(TypeError):
            self.m.move_to("1", 0.0)

    def test_bad_queries_and_layers(self):
        for bad in (np.zeros((4, 3)), np.zeros(4), np.zeros((4, 2), dtype=np.int32)):
            self.refused("invalid_argument", lambda: self.m.query_many(bad), False)
        for k in (-1, 5):
            self.refused("invalid_argument", lambda: self.m.layer(k), False)
            self.refused("invalid_argument", lambda: self.m.layer_grid(k, "height"), False)
            self.refused("invalid_argument", lambda: self.m.query(1.0, 0.0, layer=k), False)
        self.refused("invalid_argument", lambda: self.m.layer_grid(1, "ix"), False)
        self.refused("invalid_argument", lambda: self.m.layer_grid(1, "colour"), False)
        with self.assertRaises(TypeError):
            self.m.layer(1.0)

    def test_corrupt_and_foreign_snapshots(self):
        good = self.m.snapshot()
        flipped = bytearray(good)
        flipped[len(good) // 2] ^= 0x10
        for data, status in [(bytes(flipped), "corrupt"), (good[:-1], "corrupt"), (good + b"\0", "corrupt"),
                             (b"", "corrupt"), (b"CCMX" + bytes(100), "corrupt"),
                             (b"CCMS" + bytes(100), "version_mismatch")]:  # format version 0
            with self.assertRaises(ccmap.StatusError) as refusal:
                ccmap.Map.from_snapshot(data)
            self.assertEqual(refusal.exception.status, status)
        with self.assertRaises(ccmap.StatusError) as refusal:
            ccmap.Map.from_snapshot(good, preset="ccm")
        self.assertEqual(refusal.exception.status, "version_mismatch")
        self.assertEqual(ccmap.Map.from_snapshot(good, preset="cadre").preset, "cadre")
        self.assertEqual(ccmap.Map.from_snapshot(bytearray(good)).preset, "cadre")
        with self.assertRaises(TypeError):
            ccmap.Map.from_snapshot("not bytes")
        with self.assertRaises(ccmap.StatusError):
            ccmap.Map.from_snapshot(good, preset="nope")


class BadValuesInsideGoodArrays(unittest.TestCase):
    """NaN, Inf and out-of-range coordinates and bad weights inside a well-formed array are the
    library's business: counted per point, the good points used. The map then equals one fed
    only the good points, in the same order."""

    def test_bad_points_are_counted_and_the_good_ones_used(self):
        good = ground(2000, 3).astype(np.float32)
        mixed = good.copy()
        bad_rows = {3: (np.nan, 0, 0), 10: (0, np.inf, 0), 17: (0, 0, -np.inf), 24: (2e5, 0, 0), 31: (0, -3e5, 0),
                    38: (60.0, 0, 0)}
        for row, value in bad_rows.items():
            mixed = np.insert(mixed, row, value, axis=0)
        a, b = ccmap.Map("cadre"), ccmap.Map("cadre")
        counts = a.update(mixed, SENSOR)
        expected = b.update(good, SENSOR)
        self.assertEqual(counts["received"], len(good) + 6)
        self.assertEqual(counts["rejected_non_finite"], 3)
        self.assertEqual(counts["rejected_out_of_range"], 2)
        self.assertEqual(counts["outside_map"] + counts["too_noisy"], expected["outside_map"] + expected["too_noisy"] + 1)
        self.assertEqual(counts["used"], expected["used"])
        self.assertEqual(state(a)[:2], state(b)[:2])

    def test_bad_weights_are_counted_and_the_good_ones_used(self):
        points = ground(2000, 4)
        weights = np.random.default_rng(5).uniform(0.5, 2.0, len(points))
        bad = {7: 0.0, 8: -1.0, 9: np.nan, 10: np.inf, 11: 2e6}
        weights_mixed = weights.copy()
        for i, w in bad.items():
            weights_mixed[i] = w
        keep = np.ones(len(points), dtype=bool)
        keep[list(bad)] = False
        # A lidar routes every point: a weight is checked only for points routed to a layer.
        a, b = ccmap.Map("ccm", sensor="lidar"), ccmap.Map("ccm", sensor="lidar")
        counts = a.update(points, SENSOR, weights_mixed)
        b.update(points[keep], SENSOR, weights[keep])
        self.assertEqual(counts["rejected_weight"], len(bad))
        self.assertEqual(state(a)[:2], state(b)[:2])
        self.assertEqual(counts["used"], len(points) - len(bad))
        c = ccmap.Map("ccm", sensor="lidar")
        c.update(points, SENSOR)  # the noise model's weights differ from these: the map must too
        self.assertNotEqual(state(c)[0], state(b)[0])


class PaperCell(unittest.TestCase):
    def test_paper_cell_keyword_selects_the_nine_float_cell(self):
        # A 16 cm cell of a 12 deg plane along y seen on one diagonal half (x + y < 0 about the
        # centre): the paper cell's eq. (9) gives slope_x = -b/2 and calls it covered; the full
        # cell gives the least-squares plane (slope_x = 0) and calls it unknown (issue 11).
        b = math.tan(math.radians(12.0))
        g = (np.arange(32) + 0.5) * 0.005 - 0.08
        x, y = np.meshgrid(g, g)
        keep = x + y < 0.0
        pts = np.column_stack([x[keep] + 0.08, y[keep] + 0.08, b * y[keep]])
        full, paper = ccmap.Map("ccm", cell_width=0.16), ccmap.Map("ccm", cell_width=0.16, paper_cell=True)
        self.assertFalse(full.paper_cell)
        self.assertTrue(paper.paper_cell)
        self.assertIn("paper_cell=True", repr(paper))
        for m in (full, paper):
            m.update(pts, (0.0, 0.0, 0.5))
        cf, cp = full.layer(0), paper.layer(0)
        self.assertEqual((len(cf), len(cp)), (1, 1))
        self.assertAlmostEqual(float(cf["slope_x"][0]), 0.0, delta=2e-3)
        self.assertAlmostEqual(float(cp["slope_x"][0]), -0.5 * b, delta=0.01)
        self.assertEqual((cf["class"][0], cp["class"][0]), ("unknown", "traversable"))
        self.assertEqual(ccmap.snapshot_size("ccm", paper_cell=True), ccmap.snapshot_size("ccm") - 65536 * 4)
        loaded = ccmap.Map.from_snapshot(paper.snapshot())
        self.assertTrue(loaded.paper_cell)
        self.assertEqual(state(loaded), state(paper))
        with self.assertRaisesRegex(ccmap.StatusError, "version_mismatch"):
            ccmap.Map.from_snapshot(paper.snapshot(), preset="kf")
        with self.assertRaisesRegex(ccmap.StatusError, "no CCM layer"):
            ccmap.Map("omg", paper_cell=True)
        with self.assertRaises(TypeError):
            ccmap.Map("ccm", paper_cell=1)


def rolling(n, seed, shift=(0.0, 0.0, 0.0)):
    """n points over rolling ground in front of SENSOR (0.3 .. 4.5 m, +-57 deg), float32; the
    ground seen by a rover whose pose is off by -shift (the registration should answer +shift)."""
    rng = np.random.default_rng(seed)
    r = np.sqrt(0.09 + rng.random(n) * (4.5 ** 2 - 0.09))
    a = (2.0 * rng.random(n) - 1.0) * 1.0
    x, y = r * np.cos(a), r * np.sin(a)
    z = 0.06 * np.sin(2 * np.pi * x / 1.3) * np.cos(2 * np.pi * y / 1.1) + 0.04 * np.sin(2 * np.pi * (x + 0.6 * y) / 2.3)
    return np.column_stack([x - shift[0], y - shift[1], z - shift[2]]).astype(np.float32)


REGISTRATION_KEYS = {"dx", "dy", "dz", "dyaw", "sigma_dx", "sigma_dy", "sigma_dz", "sigma_dyaw", "observable",
                     "iterations", "status"}


class Registration(unittest.TestCase):
    def setUp(self):
        self.m = ccmap.Map("cadre")
        for k in range(3):
            self.m.update(rolling(40000, 100 + k), sensor_origin=SENSOR)

    def test_register_answers_the_shift_and_leaves_the_map_alone(self):
        before = state(self.m)
        r = self.m.register(rolling(40000, 7, shift=(0.03, -0.02, 0.015)), SENSOR)
        self.assertEqual(state(self.m), before, "registration changed the map")
        self.assertTrue(REGISTRATION_KEYS <= set(r), "keys missing: %s" % (REGISTRATION_KEYS - set(r)))
        self.assertEqual(r["status"], "ok")
        self.assertEqual(r["observable"], (True, True, True, True))
        for key, truth in (("dx", 0.03), ("dy", -0.02), ("dz", 0.015)):
            self.assertLess(abs(r[key] - truth), 3 * r["sigma_" + key] + 1e-3, "%s off: %r" % (key, r))
        self.assertLess(abs(r["dyaw"]), 3 * r["sigma_dyaw"] + 1e-3)
        self.assertGreaterEqual(r["iterations"], 1)

    def test_register_sensor_agrees_with_register(self):
        f = rolling(40000, 8, shift=(0.01, 0.0, 0.01))
        a = self.m.register(f, SENSOR)
        b = self.m.register_sensor(f - np.array(SENSOR, dtype=np.float32), np.eye(3), SENSOR)
        self.assertEqual(b["status"], "ok")
        for key in ("dx", "dy", "dz", "dyaw"):
            self.assertAlmostEqual(a[key], b[key], delta=2e-4)

    def test_flat_ground_claims_the_height_only(self):
        m = ccmap.Map("cadre")
        flat = rolling(40000, 1)
        flat[:, 2] = 0.0
        m.update(flat, sensor_origin=SENSOR)
        m.update(flat, sensor_origin=SENSOR)
        flat[:, 2] = -0.02
        r = m.register(flat, SENSOR)
        self.assertEqual(r["status"], "ok")
        self.assertEqual(r["observable"], (False, False, True, False))
        self.assertEqual((r["dx"], r["dy"], r["dyaw"]), (0.0, 0.0, 0.0))
        self.assertTrue(math.isinf(r["sigma_dx"]) and math.isinf(r["sigma_dyaw"]))
        self.assertAlmostEqual(r["dz"], 0.02, delta=1e-3)

    def test_refusals_are_answers_not_exceptions(self):
        f = rolling(1000, 9)
        for origin, status in (((math.nan, 0.0, 0.2), "non_finite_input"), ((40.0, 0.0, 0.2), "outside_map")):
            r = self.m.register(f, origin)
            self.assertEqual(r["status"], status)
            self.assertEqual((r["dx"], r["dz"]), (0.0, 0.0))
            self.assertEqual(r["observable"], (False, False, False, False))
            self.assertTrue(math.isinf(r["sigma_dz"]))
        self.assertEqual(self.m.register(f[:0], SENSOR)["status"], "degenerate_input")
        self.assertEqual(ccmap.Map("cadre").register(f, SENSOR)["status"], "insufficient_overlap")

    def test_bad_arguments_raise(self):
        with self.assertRaises(ccmap.StatusError) as e:
            self.m.register(np.zeros((10, 2)), SENSOR)
        self.assertEqual(e.exception.status, "invalid_argument")
        with self.assertRaises(TypeError):
            self.m.register(rolling(100, 1), SENSOR, max_pointz=5)
        with self.assertRaises(ccmap.StatusError):
            self.m.register(rolling(100, 1), SENSOR, max_points=0)
        r = self.m.register(rolling(40000, 10), SENSOR, max_points=200)
        self.assertLessEqual(r["points_sampled"], 200, "max_points did not reach the library")

    def test_align_snapshot_takes_a_believed_offset_back(self):
        r = self.m.align_snapshot(self.m.snapshot(), (0.02, 0.0, 0.0))
        self.assertEqual(r["status"], "ok")
        self.assertTrue(r["observable"][0])
        self.assertAlmostEqual(r["dx"], -0.02, delta=2e-3)
        self.assertGreater(r["cells"], 100)
        self.assertEqual(self.m.align_snapshot(b"junk", (0.0, 0.0, 0.0))["status"], "corrupt")


class SaveLoad(unittest.TestCase):
    def test_round_trip_for_every_preset(self):
        xy = np.column_stack([np.linspace(-0.5, 3.0, 300), np.linspace(-1.5, 1.5, 300)])
        for preset in ccmap.PRESETS:
            with self.subTest(preset=preset), tempfile.TemporaryDirectory() as tmp:
                m = ccmap.Map(preset)
                m.move_to(0.3, -0.2)
                m.update(ground(4000, 6), SENSOR)
                m.update_sensor(ground(2000, 7), np.eye(3), (0.1, 0.0, 0.2))
                with self.assertRaises(ccmap.StatusError):
                    m.move_to(np.nan, 0)
                path = os.path.join(tmp, "map.ccms")
                m.save(path)
                self.assertEqual(os.path.getsize(path), ccmap.snapshot_size(preset))
                for loaded in (ccmap.Map.load(path), ccmap.Map.load(path, preset=preset)):
                    self.assertEqual(loaded.preset, preset)
                    self.assertEqual(state(loaded), state(m))
                    self.assertEqual((loaded.rejected_moves, loaded.rejected_frames), (1, 0))
                    self.assertEqual(loaded.params, m.params)
                    self.assertEqual(loaded.query_many(xy).tobytes(), m.query_many(xy).tobytes())
                    self.assertIn("ok", set(m.query_many(xy)["status"]))
                # The loaded map lives on: the same next frame leaves both maps equal.
                loaded = ccmap.Map.load(path)
                for each in (m, loaded):
                    each.update(ground(1000, 8), SENSOR)
                self.assertEqual(state(loaded), state(m))

    def test_unwritable_path_is_an_os_error(self):
        with self.assertRaises(OSError):
            ccmap.Map().save("/nonexistent-dir/map.ccms")
        with self.assertRaises(OSError):
            ccmap.Map.load("/nonexistent-dir/map.ccms")


class Outputs(unittest.TestCase):
    def test_query_keys_are_the_cli_keys(self):
        m = ccmap.Map()
        m.update(ground(3000, 9), SENSOR)
        answer = m.query(1.0, 0.1)
        self.assertEqual(list(answer), CLI_QUERY_KEYS)
        self.assertEqual(answer["status"], "ok")
        self.assertEqual(list(m.query_many(np.zeros((0, 2))).dtype.names), CLI_QUERY_KEYS)
        outside = m.query(500.0, 0.0)
        self.assertEqual((outside["status"], outside["layer"]), ("outside_map", -1))
        self.assertTrue(math.isnan(outside["height_m"]))
        unknown = m.query(-1.0, 0.0)  # behind the sensor: inside the windows, never seen
        self.assertEqual((unknown["status"], unknown["layer"], unknown["class"]), ("unknown", 0, "unknown"))
        self.assertEqual(unknown["cell_width_m"], m.cell_widths[0])

    def test_layer_columns_are_the_csv_columns(self):
        with open(os.path.join(SOURCE_DIR, "tools", "io", "csv_writer.hpp")) as f:
            header = re.search(r'kLayerCsvHeader =\s*"([^"]+)"', f.read()).group(1)
        self.assertEqual(list(ccmap.Map().layer(0).dtype.names), header.split(","))

    def test_layer_grid_orientation_and_nan_where_unobserved(self):
        m = ccmap.Map("cadre")
        for k in range(m.layer_count):
            for field in ("height", "weight", "class", "normal_var"):
                grid = m.layer_grid(k, field)
                self.assertEqual(grid.shape, (m.sides[k], m.sides[k]))
                self.assertEqual(grid.dtype, np.float32)
                self.assertTrue(np.isnan(grid).all(), f"empty map, layer {k} {field}")
        m.move_to(0.5, 0.3)
        m.update(ground(4000, 10), SENSOR)
        for k in range(m.layer_count):
            cells, grid = m.layer(k), m.layer_grid(k, "height")
            side, (cx, cy), w = m.sides[k], m.window_centres[k], m.cell_widths[k]
            observed = ~np.isnan(grid)
            self.assertEqual(int(observed.sum()), len(cells))
            self.assertGreater(len(cells), 0)
            rows, cols = np.nonzero(observed)
            # Row r, column c is the cell (ix_min + c, iy_min + r): compare with the export.
            by_index = {(ix, iy): h for ix, iy, h in zip(cells["ix"], cells["iy"], cells["height"])}
            for r, c in zip(rows, cols):
                self.assertEqual(grid[r, c], by_index[(cx - side // 2 + c, cy - side // 2 + r)])
            x0, x1, y0, y1 = m.layer_extent(k)
            self.assertAlmostEqual(x1 - x0, side * w, places=9)
            self.assertAlmostEqual((x0 + x1) / 2, m.window_centres_m[k][0], places=9)
            self.assertAlmostEqual((y0 + y1) / 2, m.window_centres_m[k][1], places=9)
            # Cell centres inside the extent at their row/column.
            cx_grid, cy_grid = m.layer_grid(k, "cx"), m.layer_grid(k, "cy")
            np.testing.assert_allclose(cx_grid[observed], x0 + (cols + 0.5) * w, atol=1e-5)
            np.testing.assert_allclose(cy_grid[observed], y0 + (rows + 0.5) * w, atol=1e-5)
        # North up: on the plane z = 0.05 x - 0.02 y, height falls with the row index's rise.
        grid = m.layer_grid(1, "height")
        self.assertLess(np.nanmean(np.diff(grid, axis=0)), 0.0)
        self.assertGreater(np.nanmean(np.diff(grid, axis=1)), 0.0)

    def test_zero_copy_view_and_copies_agree(self):
        points = ground(3000, 11)
        maps = [ccmap.Map("ccm") for _ in range(4)]
        maps[0].update(points.astype(np.float32), SENSOR)                 # viewed
        maps[1].update(points, SENSOR)                                    # float64, rounded
        maps[2].update(np.asfortranarray(points.astype(np.float32)), SENSOR)  # column-major, copied
        maps[3].update(points.astype(np.float32).tolist(), SENSOR)        # a list of lists (float64)
        for other in maps[1:]:
            self.assertEqual(state(other), state(maps[0]))

    def test_counters_cover_every_field(self):
        counts = ccmap.Map().update(np.zeros((0, 3), dtype=np.float32), SENSOR)
        known = {"received", "used", "rejected_non_finite", "rejected_out_of_range", "rejected_weight", "outside_map",
                 "too_noisy"}
        self.assertLessEqual(known, set(counts))  # FrameCounters may gain members; these stay
        self.assertEqual(set(counts.values()), {0})
        self.assertEqual(list(counts), list(ccmap.Map().total_counters))


if __name__ == "__main__":
    raise SystemExit(main())
