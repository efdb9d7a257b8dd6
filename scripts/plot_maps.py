#!/usr/bin/python3
"""Top-down pictures of a run's maps, as Fig. 7 of Razlaw et al.: the accumulated raw points with
the dynamic tracks' trajectories beside the static map, coloured by height, same extent and scale.

Usage: plot_maps.py RUN_DIR OUTPUT_PNG
RUN_DIR is the --out folder of `ringtrack run`: raw_map.ply, static_map.ply (binary PLY, float
x y z intensity), tracks.csv and poses.txt (TUM: t x y z qx qy qz qw, the sensor in the world).
"""
import csv
import os
import struct
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

# Points drawn per panel at most: beyond it a regular subsample (the picture does not change).
MAX_POINTS = 400_000


def read_ply(path, columns=3):
    """Returns an (n, columns) float array of the first properties (x y z, intensity) of a PLY
    written by ringtrack (binary or ascii)."""
    with open(path, "rb") as f:
        header = []
        while True:
            line = f.readline()
            if not line:
                raise ValueError(f"{path}: the PLY header has no end_header line")
            line = line.decode("ascii", "replace").strip()
            header.append(line)
            if line == "end_header":
                break
        count = 0
        properties = []
        for line in header:
            parts = line.split()
            if parts[:2] == ["element", "vertex"]:
                count = int(parts[2])
            elif parts[:1] == ["property"]:
                properties.append(parts[-1])
        if properties[:3] != ["x", "y", "z"]:
            raise ValueError(f"{path}: expected properties x y z first, found {properties}")
        if "format binary_little_endian 1.0" in header:
            data = np.frombuffer(f.read(4 * len(properties) * count), dtype="<f4")
            if data.size != len(properties) * count:
                raise ValueError(f"{path}: {count} points declared, the file holds fewer")
            return data.reshape(count, len(properties))[:, :columns]
        rows = np.loadtxt(f, dtype=np.float32, ndmin=2, max_rows=count)
        return rows[:, :columns] if count else np.zeros((0, columns), np.float32)


def read_path(path):
    """The sensor's x y positions from a TUM file; empty when the file is missing."""
    if not os.path.exists(path):
        return np.zeros((0, 2))
    rows = [line.split() for line in open(path) if line.strip() and not line.startswith("#")]
    return np.array([[float(r[1]), float(r[2])] for r in rows]).reshape(-1, 2)


def read_dynamic_tracks(path):
    """x y positions of every track that was dynamic at some point, by track id."""
    tracks = {}
    dynamic = set()
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            tracks.setdefault(row["id"], []).append((float(row["x"]), float(row["y"])))
            if row["ever_dynamic"] == "1":
                dynamic.add(row["id"])
    return {i: np.array(p) for i, p in tracks.items() if i in dynamic}


def thin(points):
    if len(points) <= MAX_POINTS:
        return points
    return points[:: int(np.ceil(len(points) / MAX_POINTS))]


def draw(ax, points, extent, heights, title):
    # Highest last, so that what stands up (walls, trees, people) is drawn over the ground.
    points = thin(points[np.argsort(points[:, 2])])
    ax.scatter(points[:, 0], points[:, 1], c=points[:, 2], s=1.5, marker=".", linewidths=0,
               cmap="viridis", vmin=heights[0], vmax=heights[1], rasterized=True)
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_aspect("equal")
    ax.set_xlabel("x (m, east)")
    ax.set_ylabel("y (m, north)")
    ax.set_title(title, fontsize=10)
    ax.grid(True, linewidth=0.3, alpha=0.5)


def main(argv):
    if len(argv) != 3:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    run = argv[1]
    raw = read_ply(os.path.join(run, "raw_map.ply"))
    static = read_ply(os.path.join(run, "static_map.ply"))
    if len(raw) == 0:
        print(f"{run}/raw_map.ply: no points to draw", file=sys.stderr)
        return 1
    path = read_path(os.path.join(run, "poses.txt"))
    tracks = read_dynamic_tracks(os.path.join(run, "tracks.csv"))
    # One extent and one colour scale for both panels: the 0.5 and 99.5 % quantiles of the raw
    # points (a few far returns would otherwise shrink the scene to a dot).
    lo = np.percentile(raw[:, :2], 0.5, axis=0)
    hi = np.percentile(raw[:, :2], 99.5, axis=0)
    if len(path):
        lo, hi = np.minimum(lo, path.min(axis=0)), np.maximum(hi, path.max(axis=0))
    margin = 0.03 * max(hi - lo) + 1.0
    extent = (lo[0] - margin, hi[0] + margin, lo[1] - margin, hi[1] + margin)
    heights = tuple(np.percentile(raw[:, 2], [1, 99]))
    if heights[1] <= heights[0]:
        heights = (heights[0] - 0.5, heights[0] + 0.5)

    fig, axes = plt.subplots(1, 2, figsize=(14, 6.6), sharex=True, sharey=True,
                             layout="constrained")
    draw(axes[0], raw, extent, heights,
         f"accumulated raw points ({len(raw):,} voxels) and {len(tracks)} dynamic tracks")
    draw(axes[1], static, extent, heights, f"static map ({len(static):,} voxels)")
    for i, (track_id, p) in enumerate(sorted(tracks.items())):
        axes[0].plot(p[:, 0], p[:, 1], color="red", linewidth=0.8,
                     label="dynamic track" if i == 0 else None)
    for ax in axes:
        if len(path):
            if np.ptp(path, axis=0).max() > 0.1:  # a resting sensor has no path to draw
                ax.plot(path[:, 0], path[:, 1], color="black", linewidth=1.0, linestyle="--",
                        label="sensor path")
            ax.plot(path[0, 0], path[0, 1], marker="^", color="black", markersize=7,
                    linestyle="none", label="sensor start")
        ax.legend(loc="upper right", fontsize=8, framealpha=0.8)
    mappable = plt.cm.ScalarMappable(cmap="viridis", norm=plt.Normalize(*heights))
    fig.colorbar(mappable, ax=axes, shrink=0.8, label="height (m)")
    fig.savefig(argv[2], dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
