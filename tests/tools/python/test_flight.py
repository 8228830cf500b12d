"""The flight interface from Python (docs/integration.md, "Flight interface"): parameters as
commands, health, the map product and its decoder. References: a map built with the new
parameters from the start and fed the same frames (set_params), the map's own queries at the
product's cell centres computed here in float32 (the product), and the frames this test fed
(health)."""
import unittest

import numpy as np

import ccmap
from support import bits, main

SENSOR = (0.0, 0.0, 0.8)


def terrain(cx=0.0, cy=0.0, n=70, phase=0.0):
    """A slope with a 30 cm box, n x n points around (cx, cy), float32, map frame."""
    g = (np.arange(n, dtype=np.float64) + 0.5 + phase) / n * 1.8 - 0.9
    dx, dy = np.meshgrid(g, g)
    box = (dx > 0.3) & (dx < 0.6) & (np.abs(dy) < 0.2)
    z = 0.05 * (cx + dx) + 0.3 * box
    return np.column_stack([(cx + dx).ravel(), (cy + dy).ravel(), z.ravel()]).astype(np.float32)


def feed(m):
    m.update(terrain(), SENSOR)
    m.update(terrain(phase=0.5), SENSOR)
    m.move_to(0.3, 0.1)
    m.update(terrain(0.3, 0.1, phase=0.25), (0.3, 0.1, 0.8))


def same_cells(a, b):
    """Snapshots that agree in every byte but the last frame's duration and the CRC over it."""
    sa, sb = a.snapshot(), b.snapshot()
    return len(sa) == len(sb) and sa[:-12] == sb[:-12]


class Params(unittest.TestCase):
    def test_validate_answers_what_construction_answers(self):
        for kwargs in ({}, {"coverage_tau": 1.5}, {"coverage_tau": float("nan")}, {"outlier_gate_sigma": 0.5},
                       {"finest_max_sigma_m": 1.0}, {"sensor": "lidar", "lidar_sigma_m": -1.0}):
            try:
                ccmap.Map("cadre", **kwargs)
                expected = "ok"
            except ccmap.StatusError as e:
                expected = e.status
            self.assertEqual(ccmap.validate_params("cadre", **kwargs), expected, kwargs)

    def test_set_params_is_init_with_the_new_parameters(self):
        for change in ({"coverage_tau": 0.6, "max_inclination": 0.2}, {"outlier_gate_sigma": 0.0},
                       {"frame_point_budget": 3000}, {"free_space_rays": 0.0}, {"weight_limit": 40.0},
                       {"weight_mode": "inverse_variance", "reference_range_m": 1.0}):
            a = ccmap.Map("cadre")
            a.set_params(**change)
            b = ccmap.Map("cadre", **change)
            feed(a)
            feed(b)
            self.assertTrue(same_cells(a, b), change)
            self.assertEqual(a.health()["params_changes"], 1)

    def test_set_params_keeps_cells_and_refusals_change_nothing(self):
        m = ccmap.Map("cadre")
        feed(m)
        def cells():
            return [m.layer(k)[f].tobytes() for k in range(m.layer_count) for f in ("ix", "iy", "weight", "height")]
        before_change = cells()
        m.set_params(max_inclination=5.0, obstacle_fraction=0.5)
        self.assertEqual(before_change, cells())
        before = m.snapshot()
        for bad, needs in (({"cell_width": 0.05}, "finest_cell_width_m"), ({"focal_px": 500.0}, "noise"),
                           ({"coverage_tau": 1.5}, None)):
            with self.assertRaises(ccmap.StatusError) as raised:
                m.set_params(**bad)
            self.assertEqual(raised.exception.status, "invalid_argument")
            if needs:
                self.assertIn(needs, str(raised.exception))
            self.assertEqual(m.snapshot(), before, bad)


class Health(unittest.TestCase):
    def test_counts_what_was_done(self):
        m = ccmap.Map("cadre")
        feed(m)
        with self.assertRaises(ccmap.StatusError):
            m.move_to(float("nan"), 0.0)
        with self.assertRaises(ccmap.StatusError):
            m.update(terrain(), (float("inf"), 0.0, 0.0))
        h = m.health()
        self.assertEqual((h["frames_accepted"], h["frames_refused"], h["moves_refused"]), (3, 1, 1))
        self.assertEqual(h["points_received"], 3 * 70 * 70)
        self.assertEqual(h["state"], "ok")
        self.assertEqual(h["map_sequence"], 3)
        layer0 = m.layer(0)
        self.assertEqual(h["layers"][0]["observed_cells"], int(np.count_nonzero(layer0["weight"] > 0)))
        for k, layer in enumerate(h["layers"]):
            self.assertEqual((layer["centre_index_x"], layer["centre_index_y"]), m.window_centres[k])
        m.reset_counters()
        h2 = m.health()
        self.assertEqual((h2["frames_accepted"], h2["frames_refused"], h2["moves_refused"], h2["points_received"]),
                         (0, 0, 0, 0))
        self.assertEqual(h2["map_sequence"], 3)
        self.assertEqual(h2["layers"][0]["observed_cells"], h["layers"][0]["observed_cells"])


class Product(unittest.TestCase):
    def test_every_cell_is_the_query_at_its_centre(self):
        m = ccmap.Map("cadre")
        feed(m)
        for layer in range(m.layer_count):
            for answer in ("stack", "layer"):
                d = ccmap.decode_product(m.product(layer, answer, pose=(1.0, 2.0, 0.5, 0.25), tag=7))
                self.assertEqual((d["layer"], d["answer"], d["tag"], d["pose_yaw"]), (layer, answer, 7, 0.25))
                side = m.sides[layer]
                self.assertEqual((d["side_x"], d["side_y"]), (side, side))
                w = np.float32(d["cell_width_m"])
                cells = d["cells"]
                known = 0
                for row in range(side):
                    for col in range(side):
                        x = (np.float32(d["min_index_x"] + col) + np.float32(0.5)) * w
                        y = (np.float32(d["min_index_y"] + row) + np.float32(0.5)) * w
                        q = m.query(float(x), float(y), layer=None if answer == "stack" else layer)
                        c = cells[row, col]
                        self.assertEqual(ccmap.STATUS_NAMES[c["status"]], q["status"])
                        self.assertEqual(ccmap.CLASS_NAMES[c["cell_class"]], q["class"])
                        if q["status"] == "ok":
                            known += 1
                            self.assertEqual(c["layer"], q["layer"])
                            self.assertEqual(bits(c["height_m"]), bits(q["height_m"]))
                            self.assertEqual(bits(c["inclination"]), bits(q["inclination"]))
                self.assertGreater(known, 3)

    def test_decoder_refuses_damaged_bytes(self):
        m = ccmap.Map("cadre")
        feed(m)
        data = bytearray(m.product(2))
        self.assertEqual(ccmap.decode_product(bytes(data))["product_sequence"], 1)
        data[500] ^= 0x10
        with self.assertRaises(ccmap.StatusError) as raised:
            ccmap.decode_product(bytes(data))
        self.assertEqual(raised.exception.status, "corrupt")
        with self.assertRaises(ccmap.StatusError):
            ccmap.decode_product(b"CCMP")


if __name__ == "__main__":
    raise SystemExit(main())
