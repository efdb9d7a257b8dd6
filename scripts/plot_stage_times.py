#!/usr/bin/python3
"""Plots time per pipeline stage over each benchmark sequence (like Fig. 6 of Razlaw et al.).

Usage: plot_stage_times.py TIMING_CSV OUTPUT_PNG
TIMING_CSV is the benchmark's timing.csv: case,scenario,sensor,scan,<stage>_ms...,total_ms.
"""
import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(argv):
    if len(argv) != 3:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    with open(argv[1], newline="") as f:
        reader = csv.DictReader(f)
        stages = [c[:-3] for c in reader.fieldnames if c.endswith("_ms") and c != "total_ms"]
        cases = {}
        for row in reader:
            series = cases.setdefault(row["case"], {s: [] for s in stages})
            for s in stages:
                series[s].append(float(row[s + "_ms"]))
    if not cases:
        print(f"{argv[1]}: no rows", file=sys.stderr)
        return 1
    n = len(cases)
    cols = 2 if n > 1 else 1
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(7 * cols, 2.6 * rows), squeeze=False)
    for ax, (name, series) in zip(axes.flat, cases.items()):
        scans = range(len(series[stages[0]]))
        ax.stackplot(scans, [series[s] for s in stages], labels=stages, linewidth=0)
        ax.set_title(name, fontsize=9)
        ax.set_xlabel("scan")
        ax.set_ylabel("ms per scan")
        ax.set_xlim(0, max(1, len(series[stages[0]]) - 1))
        ax.grid(alpha=0.3)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    axes.flat[0].legend(loc="upper right", fontsize=7)
    fig.suptitle("ringtrack: time per stage and scan (stacked)")
    fig.tight_layout()
    fig.savefig(argv[2], dpi=90)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
