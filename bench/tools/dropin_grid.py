#!/usr/bin/env python3
"""The drop-in example (examples/dropin: an Embree renderer switched to rebraid::EmbreeAccel)
built as an outside project against the installed package, and its benchmark; prints JSON.

  python3 bench/tools/dropin_grid.py --prepare DIR   install build/ into DIR/prefix and build
                                                     the example in DIR/example
  python3 bench/tools/dropin_grid.py --run DIR       run DIR/example/dropin_example --bench
                                                     and print its rows as one JSON object

`dropin_example --bench` traces 640x480 camera rays through a grid of 24x24 instanced torus
knots (and the same grid flattened into one mesh) on one thread, three ways taking turns:
rtcIntersect1 on the application's own Embree scene, EmbreeAccel::intersect1 on the
re-braided structure built from it, and rtcIntersect1 on an Embree user-geometry scene that
answers through EmbreeAccel; each mode's Mrays/s is the median of 7 rounds after a warm-up.
The JSON adds the ratio of each rebraid mode to rtcIntersect1 on the same scene.

Python 3.11 standard library only; needs cmake and a C++ compiler, as the build does.
"""
import argparse
import csv
import io
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from results_io import repo_path, run as run_logged  # noqa: E402

EMBREE = "rtcIntersect1"


def run(argv):
    return run_logged(argv, log=None)


def prepare(folder, build):
    prefix, example = os.path.join(folder, "prefix"), os.path.join(folder, "example")
    run(["cmake", "--install", build, "--prefix", prefix])
    run(["cmake", "-S", "examples/dropin", "-B", example, "-DCMAKE_BUILD_TYPE=Release",
         f"-DCMAKE_PREFIX_PATH={prefix}"])
    run(["cmake", "--build", example])


def bench(folder):
    binary = os.path.join(folder, "example", "dropin_example")
    if not os.path.exists(binary):
        sys.exit(f"dropin_grid.py: {binary} is missing: run --prepare {folder} first")
    rows = list(csv.DictReader(io.StringIO(run([binary, "--bench"]))))
    result = {"rows": [], "ratios": {}}
    for row in rows:
        result["rows"].append({"scene": row["scene"], "mode": row["mode"],
                               "build_ms": float(row["build_ms"]),
                               "mrays_per_s": float(row["mrays_per_s"])})
    for scene in sorted({r["scene"] for r in result["rows"]}):
        modes = {r["mode"]: r["mrays_per_s"] for r in result["rows"] if r["scene"] == scene}
        if not modes.get(EMBREE):
            sys.exit(f"dropin_grid.py: no {EMBREE} row for the {scene} scene")
        result["ratios"][scene] = {mode: round(speed / modes[EMBREE], 4)
                                   for mode, speed in modes.items() if mode != EMBREE}
    return result


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    action = parser.add_mutually_exclusive_group(required=True)
    action.add_argument("--prepare", metavar="DIR", help="install and build the example in DIR")
    action.add_argument("--run", metavar="DIR", help="run the example built in DIR")
    parser.add_argument("--build", default="build", help="build folder (default build)")
    args = parser.parse_args()
    # DIR from where the command runs; the build folder from the repository root.
    folder = os.path.abspath(args.prepare or args.run)
    if args.prepare:
        prepare(folder, repo_path(args.build))
        return
    json.dump(bench(folder), sys.stdout, indent=1)
    print()


if __name__ == "__main__":
    main()
