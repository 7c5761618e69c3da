#!/usr/bin/python3
"""Plot per-frame times of `rebraid animate --csv` into a PNG.

Usage: plot_animate.py FRAMES.csv OUT.png

Small multiples: one panel per method, titled with its mean frame time, each frame's time
stacked from its parts (animation, object-BVH update, top-level build, render). Each panel
has its own time scale, so where a fast method's time goes stays readable beside a slow one;
the titles compare the methods. Needs matplotlib (Debian:
python3-matplotlib, run with /usr/bin/python3).
"""
import csv
import math
import sys

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    sys.exit("plot_animate.py: matplotlib is missing (install python3-matplotlib)")

PARTS = [("animation_ms", "animation"), ("update_ms", "update"), ("top_ms", "top level"),
         ("render_ms", "render")]


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: plot_animate.py FRAMES.csv OUT.png")
    series = {}
    with open(sys.argv[1], newline="") as f:
        for row in csv.DictReader(f):
            method = series.setdefault(row["method"], {"frame": [], **{k: [] for k, _ in PARTS}})
            method["frame"].append(int(row["frame"]))
            for key, _ in PARTS:
                method[key].append(float(row[key]))
    if not series:
        sys.exit(f"plot_animate.py: no rows in {sys.argv[1]}")
    columns = min(4, len(series))
    rows = math.ceil(len(series) / columns)
    fig, axes = plt.subplots(rows, columns, figsize=(3.2 * columns, 2.4 * rows + 0.8), dpi=100,
                             sharex=True, squeeze=False)
    colours = plt.get_cmap("tab10").colors
    for ax, (method, data) in zip(axes.flat, series.items()):
        ax.stackplot(data["frame"], *[data[key] for key, _ in PARTS],
                     labels=[label for _, label in PARTS], colors=colours[:len(PARTS)])
        mean = sum(sum(data[key]) for key, _ in PARTS) / max(1, len(data["frame"]))
        ax.set_title(f"{method}: {mean:.1f} ms/frame", fontsize="small")
        ax.grid(True, alpha=0.3)
        ax.set_ylim(bottom=0)
    for ax in list(axes.flat)[len(series):]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("frame")
    for ax in axes[:, 0]:
        ax.set_ylabel("ms per frame")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    top = 1 - 0.7 / fig.get_figheight()  # room for the title and the legend, in inches
    fig.suptitle("rebraid animate: frame time per method and where it goes", y=0.995,
                 fontsize="medium")
    fig.legend(handles, labels, loc="lower center", bbox_to_anchor=(0.5, top), ncol=len(PARTS),
               fontsize="small", frameon=False)
    fig.tight_layout(rect=(0, 0, 1, top))
    fig.savefig(sys.argv[2])


if __name__ == "__main__":
    main()
