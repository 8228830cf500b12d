#!/usr/bin/python3
"""Map the Lone Star Geyser laser scan with the ccmap Python module and plot one layer.

    PYTHONPATH=build/host-release/tools/python /usr/bin/python3 examples/python/map_laser_scan.py
    ... map_laser_scan.py --source las --out out/python/lone_star_full.png     # the whole scan

Reads the 10 x 10 m crop (text, x y z) or the full scan (LAS 1.0-1.4, parsed with numpy) from
the team's data set (--data DIR, else $CCMAP_DATA_DIR, else ../shared/data beside the
repository); without it the script says so and exits 0 (exit code 77 with --skip-code).
The UTM coordinates are made local in float64 (minus the centre of the scan, rounded to a
whole cell) before anything becomes float32. One CCM layer (preset "ccm") with a lidar
noise model (5 mm) takes every point; the picture shows the layer's height (absolute, m) and
its classes, north up, in UTM metres. Writes a PNG (matplotlib, Agg backend).
"""
import argparse
import os
import sys

import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)
from matplotlib.colors import ListedColormap  # noqa: E402

import ccmap  # noqa: E402

CROP = "lone_star_tls/lone_star_crop_10x10m_x515386.6_y4918368.4.xyz"
LAS = "lone_star_tls/lone-star.las"


def default_data_dir():
    env = os.environ.get("CCMAP_DATA_DIR")
    if env:
        return env
    repository = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    return os.path.join(os.path.dirname(repository), "shared", "data")


def read_las(path):
    """x, y, z (float64, metres) of a LAS 1.0-1.4 file: the header's scale and offset applied
    to the integer X, Y, Z at the start of every point record."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:4] != b"LASF":
        raise ValueError(f"{path}: not a LAS file")
    header = np.frombuffer(data, count=1, dtype=np.dtype([
        ("skip0", "V96"), ("point_offset", "<u4"), ("vlr_count", "<u4"), ("format", "u1"),
        ("record_length", "<u2"), ("legacy_count", "<u4"), ("skip1", "V20"),
        ("scale", "<f8", 3), ("offset", "<f8", 3)]))[0]
    count = int(header["legacy_count"])
    if count == 0 and data[24:26] >= bytes([1, 4]):  # LAS 1.4: 64-bit count at byte 247
        count = int(np.frombuffer(data, dtype="<u8", count=1, offset=247)[0])
    length = int(header["record_length"])
    records = np.frombuffer(data, dtype=np.dtype({"names": ["xyz"], "formats": [("<i4", 3)], "itemsize": length}),
                            count=count, offset=int(header["point_offset"]))
    return records["xyz"] * header["scale"] + header["offset"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--source", choices=["crop", "las"], default="crop", help="the 10 m crop or the full LAS scan")
    parser.add_argument("--data", default=None, help="data directory (default: $CCMAP_DATA_DIR or ../shared/data)")
    parser.add_argument("--cell-width", type=float, default=None, help="m (default: 0.16)")
    parser.add_argument("--out", default=None, help="PNG to write (default: out/python/lone_star_<source>.png)")
    parser.add_argument("--skip-code", action="store_true", help="exit 77 (not 0) when the data is absent")
    args = parser.parse_args()

    data_dir = args.data or default_data_dir()
    path = os.path.join(data_dir, CROP if args.source == "crop" else LAS)
    if not os.path.isfile(path):
        print(f"map_laser_scan: skipped: {path} is not available (the shared data set is not part of the "
              "repository; point at it with --data DIR or CCMAP_DATA_DIR)")
        return 77 if args.skip_code else 0

    utm = np.loadtxt(path, dtype=np.float64) if args.source == "crop" else read_las(path)
    # 256 x 256 cells of 16 cm: a 41 m window holds the 32 x 41 m scan (~10 points per cell).
    cell_width = args.cell_width or 0.16
    m = ccmap.Map("ccm", cell_width=cell_width, sensor="lidar", lidar_sigma_m=0.005)

    # Local origin in float64: the centre of the bounding box rounded to a whole cell; the window,
    # centred on it, then covers the scan.
    origin = np.round((utm.min(axis=0) + utm.max(axis=0)) / 2 / cell_width) * cell_width
    local = (utm - origin).astype(np.float32)
    m.move_to(0.0, 0.0)
    # A lidar with constant noise: the range (and so the sensor origin) only has to be finite.
    counters = m.update(local, sensor_origin=(0.0, 0.0, 2.0))
    print(f"{path}: {len(local)} points, origin (UTM) {origin[0]:.2f} {origin[1]:.2f} {origin[2]:.2f}")
    print("frame counters:", ", ".join(f"{k} {v}" for k, v in counters.items() if v))

    cells = m.layer(0)
    classes, counts = np.unique(cells["class"], return_counts=True)
    print(f"layer 0 ({cell_width * 100:g} cm): {len(cells)} cells observed;",
          ", ".join(f"{c} {n}" for c, n in zip(classes, counts)))

    x0, x1, y0, y1 = m.layer_extent(0)
    extent = (x0 + origin[0], x1 + origin[0], y0 + origin[1], y1 + origin[1])
    height = m.layer_grid(0, "height")  # float32, NaN where unobserved
    class_grid = m.layer_grid(0, "class")
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.4), constrained_layout=True)
    # Row 0 of a layer grid is the window's lowest iy (south): origin="lower" puts north up.
    # Colours over the 2nd..98th percentile: the scan's tall returns (steam, vegetation) would
    # otherwise flatten the ground into one colour.
    low, high = np.nanpercentile(height, [2, 98]) + origin[2]
    image = axes[0].imshow(height + origin[2], origin="lower", extent=extent, cmap="terrain", vmin=low, vmax=high)
    fig.colorbar(image, ax=axes[0], label="height (m)")
    axes[0].set_title(f"Lone Star scan, {cell_width * 100:g} cm CCM: height")
    palette = ListedColormap(["0.6", "tab:green", "tab:red", "tab:orange"])  # ccmap.CLASS_NAMES order
    image = axes[1].imshow(class_grid, origin="lower", extent=extent, cmap=palette, vmin=-0.5, vmax=3.5,
                           interpolation="nearest")
    bar = fig.colorbar(image, ax=axes[1], ticks=range(len(ccmap.CLASS_NAMES)))
    bar.ax.set_yticklabels(ccmap.CLASS_NAMES)
    axes[1].set_title("classes (white: unobserved)")
    for ax in axes:
        ax.set_xlabel("UTM east (m)")
        ax.set_ylabel("UTM north (m)")
        ax.ticklabel_format(useOffset=False, style="plain")
        # The data's extent, not the whole window.
        ax.set_xlim(utm[:, 0].min(), utm[:, 0].max())
        ax.set_ylim(utm[:, 1].min(), utm[:, 1].max())

    out = args.out or os.path.join("out", "python", f"lone_star_{args.source}.png")
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
