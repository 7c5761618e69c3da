#!/usr/bin/env python3
"""The paper's evaluation on our scenes, from `rebraid bench --json` runs.

  evaluate.py tables SCENE... [--rays N]   Table 1 (SAH, Mrays/s, ratios to twolevel),
                                           Table 1b (work per diffuse ray) and Table 2 (full and
                                           top-level build times) as Markdown, for the paper's
                                           rules, the default `rebraid` and the paper's budget
                                           for trees over objects
  evaluate.py sweep SCENE... --plot P.png  Figure 4: SAH and Mrays/s against open_threshold
                                           and against the budget factor, and a plot
  evaluate.py plot --json SWEEP.json --plot P.png   the plot again from a sweep's raw results
  evaluate.py compare SCENE... --accel LIST [--baseline NAME] [--rounds K]
                                           variants side by side: SAH, Mrays/s and
                                           top build ms per scene, ratios to the baseline

Every number comes from one `rebraid bench` run per scene (and per setting in the sweep), so
the structures of a table are measured on the same rays in the same process. `compare` runs
that bench K times per scene and reports, per variant, the median over the rounds (Mrays/s of
one process move by 10-20 % with memory placement; rounds average that out); SAH is exact.
"""
import argparse
import json
import math
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_BINARY = os.path.join(HERE, "..", "build", "examples", "rebraid")
# The paper's rules alone (extent opening, transformed node boxes); plain `rebraid` is the
# project's default, which adds the sah opening and vertex bounds.
PAPER = "rebraid:opening=extent:bref-bounds=box"
# The paper's budget for trees built over objects (§5.2: #primitives / 1000) rather than over
# instances (4 x #instances, the default): its choice for scenes like powerplant and crown.
OBJECTS_BUDGET = "rebraid:budget-rule=primitives"
ACCELS = ["embree-flat", "embree-instanced", "flat", "twolevel", PAPER, "rebraid", OBJECTS_BUDGET]
THRESHOLDS = [0.0, 0.025, 0.05, 0.1, 0.2, 0.35, 0.5, 0.75, 1.0]
BUDGETS = [0.0, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0]


def bench(binary, scene, accels, rays, repetitions, extra=()):
    command = [binary, "bench", scene, "--accel", ",".join(accels), "--rays", str(rays),
               "--repetitions", str(repetitions), "--json", *extra]
    print("$ " + " ".join(command), file=sys.stderr)
    result = subprocess.run(command, check=True, capture_output=True, text=True)
    return json.loads(result.stdout)


def name_of(scene):
    return os.path.splitext(os.path.basename(scene))[0]


def ratio(value, reference):
    return f"{value / reference:.2f}x" if value and reference else "-"


def tables(args):
    # One bench run per scene: its rows, keyed by accel.
    runs = [(scene, {r["accel"]: r for r in bench(args.binary, scene, ACCELS, args.rays,
                                                   args.repetitions)}) for scene in args.scenes]
    if args.json:
        with open(args.json, "w") as out:
            json.dump([r for _, group in runs for r in group.values()], out, indent=1)
    print("### Table 1: SAH and Mrays/s (ratios to twolevel)\n")
    print("| scene | accel | SAH | SAH / twolevel | Mrays/s primary | / twolevel | Mrays/s diffuse | / twolevel |")
    print("|---|---|---|---|---|---|---|---|")
    for scene, group in runs:
        two = group["twolevel"]
        for r in group.values():
            sah = r.get("sah")
            print(f"| {name_of(scene)} | {r['accel']} | {sah:.2f} | {ratio(sah, two['sah'])} | "
                  f"{r['mrays_primary']:.2f} | {ratio(r['mrays_primary'], two['mrays_primary'])} | "
                  f"{r['mrays_diffuse']:.2f} | {ratio(r['mrays_diffuse'], two['mrays_diffuse'])} |"
                  if sah is not None else
                  f"| {name_of(scene)} | {r['accel']} | - | - | "
                  f"{r['mrays_primary']:.2f} | {ratio(r['mrays_primary'], two['mrays_primary'])} | "
                  f"{r['mrays_diffuse']:.2f} | {ratio(r['mrays_diffuse'], two['mrays_diffuse'])} |")
    print("\n### Table 1b: work per diffuse ray (counted, exact) against the speed ratio to flat\n")
    print("Nodes visited, triangles tested and object entries (top-level items a ray enters) per")
    print("diffuse ray; `work` = nodes + triangles, the two unit costs of the SAH.\n")
    print("| scene | accel | nodes | triangles | object entries | work / flat | Mrays/s diffuse / flat |")
    print("|---|---|---|---|---|---|---|")
    for scene, group in runs:
        flat = group["flat"]
        flat_work = flat["nodes_per_diffuse_ray"] + flat["triangles_per_diffuse_ray"]
        for r in group.values():
            if r.get("nodes_per_diffuse_ray") is None:
                continue  # Embree's structures count nothing
            work = r["nodes_per_diffuse_ray"] + r["triangles_per_diffuse_ray"]
            print(f"| {name_of(scene)} | {r['accel']} | {r['nodes_per_diffuse_ray']:.2f} | "
                  f"{r['triangles_per_diffuse_ray']:.2f} | {r['object_entries_per_diffuse_ray']:.2f} | "
                  f"{ratio(work, flat_work)} | {ratio(r['mrays_diffuse'], flat['mrays_diffuse'])} |")
    print("\n### Table 2: build times in ms (full build; top level only)\n")
    print("| scene | embree-flat | embree-instanced | flat | twolevel | twolevel top | paper | paper top | paper top / twolevel top | BRefs (budget) | nodes twolevel / paper | rebraid top (default) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for scene, group in runs:
        two, reb = group["twolevel"], group[PAPER]
        print(f"| {name_of(scene)} | {group['embree-flat']['build_ms']:.1f} | "
              f"{group['embree-instanced']['build_ms']:.1f} | {group['flat']['build_ms']:.1f} | "
              f"{two['build_ms']:.1f} | {two['top_build_ms']:.2f} | {reb['build_ms']:.1f} | "
              f"{reb['top_build_ms']:.2f} | {ratio(reb['top_build_ms'], two['top_build_ms'])} | "
              f"{reb['brefs']} ({reb['instances'] + reb['budget']}) | {two['nodes']} / {reb['nodes']} | "
              f"{group['rebraid']['top_build_ms']:.2f} |")


def sweep(args):
    results = {"threshold": {}, "budget": {}}
    for scene in args.scenes:
        name = name_of(scene)
        results["threshold"][name] = [
            (t, bench(args.binary, scene, [PAPER], args.rays, args.repetitions,
                      ["--open-threshold", str(t)])[0]) for t in THRESHOLDS]
        results["budget"][name] = [
            (b, bench(args.binary, scene, [PAPER], args.rays, args.repetitions,
                      ["--budget-factor", str(b)])[0]) for b in BUDGETS]
    for kind, label in (("threshold", "open_threshold"), ("budget", "budget factor")):
        print(f"\n### Figure 4 data: SAH and diffuse Mrays/s against {label}\n")
        values = THRESHOLDS if kind == "threshold" else BUDGETS
        print("| scene | " + " | ".join(f"{v:g}" for v in values) + " |")
        print("|---|" + "---|" * len(values))
        for name, points in results[kind].items():
            print(f"| {name} SAH | " + " | ".join(f"{p['sah']:.2f}" for _, p in points) + " |")
            print(f"| {name} Mrays/s | " + " | ".join(f"{p['mrays_diffuse']:.2f}" for _, p in points) + " |")
    if args.json:
        with open(args.json, "w") as out:
            json.dump(results, out, indent=1)
    if args.plot:
        plot(results, args.plot)


def median(values):
    ordered = sorted(values)
    middle = len(ordered) // 2
    return ordered[middle] if len(ordered) % 2 else 0.5 * (ordered[middle - 1] + ordered[middle])


def median_over_rounds(rounds, accel, key):
    values = [r[key] for run in rounds for r in run if r["accel"] == accel and r.get(key) is not None]
    return median(values) if values else None


def compare(args):
    accels = args.accel.split(",")
    if args.baseline not in accels:
        sys.exit(f"evaluate.py compare: the baseline {args.baseline} is not in --accel")
    metrics = [("sah", "SAH (exact; lower is better)", "{:.2f}"),
               ("mrays_primary", "primary Mrays/s (median of rounds)", "{:.2f}"),
               ("mrays_diffuse", "diffuse Mrays/s (median of rounds)", "{:.2f}"),
               ("top_build_ms", "top-level build ms (median of rounds)", "{:.2f}")]
    raw = {}
    summary = {}
    for scene in args.scenes:
        rounds = [bench(args.binary, scene, accels, args.rays, args.repetitions)
                  for _ in range(args.rounds)]
        raw[name_of(scene)] = rounds
        summary[name_of(scene)] = {accel: {key: median_over_rounds(rounds, accel, key)
                                           for key, _, _ in metrics} for accel in accels}
    if args.json:
        with open(args.json, "w") as out:
            json.dump({"raw": raw, "median": summary}, out, indent=1)
    for key, title, fmt in metrics:
        print(f"\n#### {title}, ratio to {args.baseline}\n")
        print("| scene | " + " | ".join(accels) + " |")
        print("|---|" + "---|" * len(accels))
        logs = {accel: [] for accel in accels}
        for name, group in summary.items():
            base = group[args.baseline][key]
            cells = []
            for accel in accels:
                value = group[accel][key]
                if value is None:
                    cells.append("-")
                elif accel == args.baseline or not base:
                    cells.append(fmt.format(value))
                else:
                    cells.append(f"{fmt.format(value)} ({value / base:.2f})")
                    logs[accel].append(value / base)
            print(f"| {name} | " + " | ".join(cells) + " |")
        geo = [f"{math.exp(sum(map(math.log, v)) / len(v)):.3f}" if v and all(x > 0 for x in v) else "-"
               for v in logs.values()]
        print("| geometric mean of ratios | " + " | ".join(geo) + " |")


def plot(results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    figure, axes = plt.subplots(2, 2, figsize=(11, 8))
    for column, (kind, label, default) in enumerate(
            (("threshold", "open_threshold", 0.1), ("budget", "budget factor (extra BRefs per instance)", 4.0))):
        for name, points in results[kind].items():
            xs = [x for x, _ in points]
            reference = next(p for x, p in points if x == default)
            axes[0][column].plot(xs, [p["sah"] / reference["sah"] for _, p in points], marker="o", label=name)
            axes[1][column].plot(xs, [p["mrays_diffuse"] / reference["mrays_diffuse"] for _, p in points],
                                 marker="o", label=name)
        axes[0][column].set_ylabel(f"SAH / SAH at {default:g}")
        axes[1][column].set_ylabel(f"diffuse Mrays/s / at {default:g}")
        for row in range(2):
            axes[row][column].set_xlabel(label)
            axes[row][column].grid(alpha=0.3)
    axes[0][0].legend(fontsize=8)
    figure.suptitle("rebraid: SAH and diffuse-ray speed against the opening threshold and the budget")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    print(f"\nwrote {path}", file=sys.stderr)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("mode", choices=["tables", "sweep", "plot", "compare"])
    parser.add_argument("scenes", nargs="*", help="scene files, or 'default'")
    parser.add_argument("--binary", default=DEFAULT_BINARY, help="the rebraid command")
    parser.add_argument("--rays", type=int, default=230400)
    parser.add_argument("--repetitions", type=int, default=5)
    parser.add_argument("--json", help="also write the raw results here")
    parser.add_argument("--plot", help="sweep: write the plot here (needs python3-matplotlib)")
    parser.add_argument("--accel", default=",".join(ACCELS), help="compare: the variants")
    parser.add_argument("--baseline", default="rebraid", help="compare: ratios are to this variant")
    parser.add_argument("--rounds", type=int, default=3, help="compare: bench runs per scene")
    args = parser.parse_args()
    if args.mode == "plot":
        with open(args.json) as raw:
            plot(json.load(raw), args.plot)
    else:
        {"tables": tables, "sweep": sweep, "compare": compare}[args.mode](args)


if __name__ == "__main__":
    main()
