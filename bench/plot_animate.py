#!/usr/bin/python3
"""Plot per-frame times of `rebraid animate --csv` into a PNG.

Usage: plot_animate.py FRAMES.csv OUT.png

One line per method (frame_ms = animation + update + top level + render), Embree's methods
dashed, rebraid-incremental dotted. Needs matplotlib (Debian: python3-matplotlib, run with /usr/bin/python3).
"""
import csv
import sys

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    sys.exit("plot_animate.py: matplotlib is missing (install python3-matplotlib)")


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: plot_animate.py FRAMES.csv OUT.png")
    series = {}
    with open(sys.argv[1], newline="") as f:
        for row in csv.DictReader(f):
            frames, times = series.setdefault(row["method"], ([], []))
            frames.append(int(row["frame"]))
            times.append(float(row["frame_ms"]))
    if not series:
        sys.exit(f"plot_animate.py: no rows in {sys.argv[1]}")
    fig, ax = plt.subplots(figsize=(10, 6), dpi=100)
    # tab20: a distinct colour for each of up to 20 methods (the default cycle has 10).
    colours = plt.get_cmap("tab20").colors
    for index, (method, (frames, times)) in enumerate(series.items()):
        # Embree dashed, the incremental top dotted (it shares colours' neighbours with rebraid).
        style = "--" if method.startswith("embree") else (":" if "incremental" in method else "-")
        ax.plot(frames, times, style, label=method, linewidth=1.5,
                color=colours[index % len(colours)])
    ax.set_xlabel("frame")
    ax.set_ylabel("frame time (ms): animation + update + top level + render")
    ax.set_title("rebraid animate: dynamic objects in a static scene")
    ax.set_ylim(bottom=0)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small", ncol=2)
    fig.tight_layout()
    fig.savefig(sys.argv[2])


if __name__ == "__main__":
    main()
