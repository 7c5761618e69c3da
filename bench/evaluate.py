#!/usr/bin/env python3
"""Parameter studies of the re-braided top level with `rebraid bench --json` (the benchmark
tables themselves come from bench/collect.py and bench/report.py).

  evaluate.py sweep SCENE... [--rounds K] [--json RAW.json] [--plot P.png]
      Figure 4 of the paper: SAH and diffuse Mrays/s of the paper's rules against the opening
      threshold and against the budget factor, as Markdown tables (medians over K rounds) and
      optionally a plot (needs matplotlib)
  evaluate.py plot --json RAW.json --plot P.png
      the sweep's plot again from its raw results
  evaluate.py budget SCENE... [--json RAW.json]
      budget policy: exact SAH over flat's for budget factors 1..64 under the paper's rules and
      the default rules, the per-primitive budget and the budget search (few rays: only the
      SAH counts)

SCENE is a glTF file or 'default'; paths are relative to the repository root, where every
command runs. Each setting of a scene is one `rebraid bench` process.
"""
import argparse
import json
import sys

from results_io import PAPER, bench, median, scene_name

THRESHOLDS = [0.0, 0.025, 0.05, 0.1, 0.2, 0.35, 0.5, 0.75, 1.0]
BUDGETS = [0.0, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0]
BUDGET_FACTORS = [1, 2, 4, 8, 16, 32, 64]
DEFAULT = "rebraid"
OBJECTS_BUDGET = "rebraid:budget-rule=primitives"
PAPER_OBJECTS_BUDGET = PAPER + ":budget-rule=primitives"
BUDGET_SEARCH = "rebraid:budget-doublings=4"


def median_row(rows):
    """One row whose numeric fields are the medians over `rows` (rounds of one setting)."""
    merged = dict(rows[0])
    for key, value in rows[0].items():
        if isinstance(value, float):
            merged[key] = median([r.get(key) for r in rows])
    return merged


def sweep(args):
    results = {"threshold": {}, "budget": {}}

    def point(scene, option, value):
        rows = [bench(scene, [PAPER], args.rays, args.repetitions, [option, str(value)])[0]
                for _ in range(args.rounds)]
        return value, median_row(rows)

    for scene in args.scenes:
        name = scene_name(scene)
        results["threshold"][name] = [point(scene, "--open-threshold", t) for t in THRESHOLDS]
        results["budget"][name] = [point(scene, "--budget-factor", b) for b in BUDGETS]
    for kind, label in (("threshold", "open_threshold"), ("budget", "budget factor")):
        print(f"\n### SAH and diffuse Mrays/s against {label} (paper's rules)\n")
        values = THRESHOLDS if kind == "threshold" else BUDGETS
        print("| scene | " + " | ".join(f"{v:g}" for v in values) + " |")
        print("|---|" + "--:|" * len(values))
        for name, points in results[kind].items():
            print(f"| {name} SAH | " + " | ".join(f"{p['sah']:.2f}" for _, p in points) + " |")
            print(f"| {name} Mrays/s | "
                  + " | ".join(f"{p['mrays_diffuse']:.2f}" for _, p in points) + " |")
    if args.json:
        with open(args.json, "w") as out:
            json.dump(results, out, indent=1)
    if args.plot:
        plot(results, args.plot)


def plot(results, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        sys.exit("evaluate.py: the plot needs matplotlib")
    figure, axes = plt.subplots(2, 2, figsize=(11, 8))
    for column, (kind, label, default) in enumerate(
            (("threshold", "open_threshold", 0.1),
             ("budget", "budget factor (extra BRefs per instance)", 4.0))):
        for name, points in results[kind].items():
            xs = [x for x, _ in points]
            reference = next(p for x, p in points if x == default)
            axes[0][column].plot(xs, [p["sah"] / reference["sah"] for _, p in points],
                                 marker="o", label=name)
            axes[1][column].plot(xs, [p["mrays_diffuse"] / reference["mrays_diffuse"]
                                      for _, p in points], marker="o", label=name)
        axes[0][column].set_ylabel(f"SAH / SAH at {default:g}")
        axes[1][column].set_ylabel(f"diffuse Mrays/s / at {default:g}")
        for row in range(2):
            axes[row][column].set_xlabel(label)
            axes[row][column].grid(alpha=0.3)
    axes[0][0].legend(fontsize=8)
    figure.suptitle("rebraid: SAH and diffuse-ray speed against the opening threshold and the budget")
    figure.tight_layout()
    figure.savefig(path, dpi=110, metadata={"Software": None})
    print(f"wrote {path}", file=sys.stderr)


def budget(args):
    accels = ["flat", "twolevel"]
    for factor in BUDGET_FACTORS:
        accels += [f"{PAPER}:budget-factor={factor}", f"{DEFAULT}:budget-factor={factor}"]
    accels += [PAPER_OBJECTS_BUDGET, OBJECTS_BUDGET, BUDGET_SEARCH]
    runs = [(scene_name(s), {r["accel"]: r for r in bench(s, accels, args.rays, 1)})
            for s in args.scenes]
    if args.json:
        with open(args.json, "w") as out:
            json.dump({name: list(rows.values()) for name, rows in runs}, out, indent=1)
    for rule, prefix, objects in (("paper", PAPER, PAPER_OBJECTS_BUDGET),
                                  ("default (sah opening, vertex bounds)", DEFAULT, OBJECTS_BUDGET)):
        print(f"\n### SAH / flat SAH by budget factor, {rule} rules (best factor in bold)\n")
        header = (["scene", "instances", "twolevel"] + [f"B={f}" for f in BUDGET_FACTORS]
                  + ["primitives / 1000 (budget)"])
        if prefix == DEFAULT:
            header.append("search from 4 (budget)")
        print("| " + " | ".join(header) + " |")
        print("|---|" + "--:|" * (len(header) - 1))
        for name, rows in runs:
            flat = rows["flat"]["sah"]
            sahs = [rows[f"{prefix}:budget-factor={f}"]["sah"] for f in BUDGET_FACTORS]
            cells = [name, str(rows["twolevel"]["instances"]), f"{rows['twolevel']['sah'] / flat:.3f}"]
            cells += [f"**{x / flat:.3f}**" if x == min(sahs) else f"{x / flat:.3f}" for x in sahs]
            cells.append(f"{rows[objects]['sah'] / flat:.3f} ({rows[objects]['budget']})")
            if prefix == DEFAULT:
                search = rows[BUDGET_SEARCH]
                cells.append(f"{search['sah'] / flat:.3f} ({search['budget']})")
            print("| " + " | ".join(cells) + " |")


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("mode", choices=["sweep", "plot", "budget"])
    parser.add_argument("scenes", nargs="*", help="scene files, or 'default'")
    parser.add_argument("--rays", type=int, help="rays of each kind (sweep: 230400, budget: 16)")
    parser.add_argument("--repetitions", type=int, default=5, help="sweep: timed runs per process")
    parser.add_argument("--rounds", type=int, default=1,
                        help="sweep: processes per setting; the median counts")
    parser.add_argument("--json", help="write (plot: read) the raw results here")
    parser.add_argument("--plot", help="sweep, plot: write the plot here (needs matplotlib)")
    args = parser.parse_args()
    if args.mode == "plot":
        if not args.json or not args.plot:
            parser.error("plot needs --json and --plot")
        with open(args.json) as raw:
            plot(json.load(raw), args.plot)
        return
    if not args.scenes:
        parser.error(f"{args.mode} needs at least one SCENE")
    if args.rays is None:
        args.rays = 16 if args.mode == "budget" else 230400
    {"sweep": sweep, "budget": budget}[args.mode](args)


if __name__ == "__main__":
    main()
