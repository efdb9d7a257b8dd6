#!/usr/bin/python3
"""Top-down picture of the dynamic-object filter's errors (the third Fig. 7-style picture): points
of moving objects the filter kept (red) and static points it removed (blue), over the static points
it kept (grey).

Usage: plot_map_errors.py POINTS_PLY OUTPUT_PNG
POINTS_PLY is written by `ringtrack eval --map-errors-png`: x y z and, as intensity, the kind of
each point (0 static kept, 1 dynamic kept, 2 static removed), world frame.
"""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plot_maps import read_ply, thin  # noqa: E402


def main(argv):
    if len(argv) != 3:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    points = read_ply(argv[1], columns=4)
    if len(points) == 0:
        print(f"{argv[1]}: no points to draw", file=sys.stderr)
        return 1
    kind = points[:, 3].round().astype(int)
    lo = np.percentile(points[:, :2], 0.5, axis=0)
    hi = np.percentile(points[:, :2], 99.5, axis=0)
    margin = 0.03 * max(hi - lo) + 1.0
    fig, ax = plt.subplots(figsize=(8, 7.5), layout="constrained")
    layers = [(0, "lightgrey", 1.0, "static points kept (0.2 m voxels)"),
              (1, "red", 4.0, "dynamic points kept (should be gone)"),
              (2, "blue", 4.0, "static points removed (should stay)")]
    for value, colour, size, label in layers:
        p = thin(points[kind == value])
        ax.scatter(p[:, 0], p[:, 1], s=size, c=colour, marker=".", linewidths=0, rasterized=True,
                   label=f"{label}: {int((kind == value).sum()):,}")
    ax.set_xlim(lo[0] - margin, hi[0] + margin)
    ax.set_ylim(lo[1] - margin, hi[1] + margin)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m, east)")
    ax.set_ylabel("y (m, north)")
    ax.set_title("dynamic-object filter: what it kept and removed wrongly", fontsize=10)
    ax.grid(True, linewidth=0.3, alpha=0.5)
    ax.legend(loc="upper right", fontsize=8, framealpha=0.8, markerscale=4)
    fig.savefig(argv[2], dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
