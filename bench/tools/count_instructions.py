#!/usr/bin/env python3
"""Exact instructions per ray of each structure on one scene, counted by callgrind.

  python3 bench/tools/count_instructions.py SCENE [--rays N] [--accel LIST] [--jobs J]

SCENE is a glTF file or `default`. The tool writes the bench's rays with
`rebraid bench SCENE --save-rays` (N primary rays of the auto-framed camera and N diffuse
bounce rays, as `rebraid bench` traces them) into a temporary folder, then runs
`build/bench/trace_rays SCENE PRIMARY DIFFUSE ACCEL` under callgrind once per structure: one
build, then one `trace_all` call per ray file, each finding every ray's closest hit, then
every ray's occlusion (Embree's structures on rays already in Embree's layout). callgrind dumps its counts on every entry into trace_all, so each ray file's
instructions are trace_all's inclusive cost in its own dump: the tracing only, without the
scene loading and the build (which valgrind still emulates, slowly). It prints one JSON
object: instructions per primary and per diffuse ray of each structure, the ray and hit counts
and the exact commands (WORK stands for the temporary folder).

The count is exact and the same on every run and machine load. valgrind emulates no AVX-512,
so Embree picks its AVX2 kernels and the project's structures theirs: both sides compare at
AVX2. Time: valgrind runs about 50 times slower than the native code and the builds dominate.
With 10,000 rays of each kind and --jobs 2 on 2 cores: 10 to 20 s for a shared scene, 1.3 min
for the default scene and 5 min for the generated `trees` (10 million triangles, whose
embree-flat build alone takes 4 minutes under valgrind).

Python 3.11 standard library only.
"""
import argparse
import concurrent.futures
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from results_io import (BINARY, DEFAULT_ACCELS, TRACER, repo_path, run,  # noqa: E402
                        scene_name)

# The structures trace_rays builds.
ACCELS = DEFAULT_ACCELS
KINDS = ["primary", "diffuse"]
# Stands for the tool's temporary folder in recorded commands.
WORK = "WORK"
TRACE_FUNCTION = "*trace_all*"


def callgrind_command(scene, ray_files, accel, out_file):
    """valgrind argv that dumps counts on each entry into trace_all: the dumps after the first
    each hold one trace_all call (and what runs after it until the next dump)."""
    return ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out_file}",
            f"--dump-before={TRACE_FUNCTION}", TRACER, scene, *ray_files, accel]


def trace_all_cost(dump_file):
    """The inclusive instruction count of trace_all in one callgrind dump (None if the dump
    holds no call of it)."""
    text = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", dump_file],
                          check=True, capture_output=True, text=True).stdout
    for line in text.splitlines():
        match = re.match(r"\s*([\d,]+)\s+\([\d.]+%\)\s+\S.*\btrace_all\(", line)
        if match:
            return int(match.group(1).replace(",", ""))
    return None


def dump_files(out_file):
    """callgrind's dumps of one run in order: out_file.1, out_file.2, ..., then out_file (the
    dump at program termination)."""
    numbered = []
    folder, base = os.path.split(out_file)
    for name in os.listdir(folder):
        match = re.fullmatch(re.escape(base) + r"\.(\d+)", name)
        if match:
            numbered.append((int(match.group(1)), os.path.join(folder, name)))
    return [path for _, path in sorted(numbered)] + [out_file]


def count_structure(scene, ray_files, accel, work):
    """Instructions and trace_rays' summary per ray file for one structure."""
    out_file = os.path.join(work, f"{accel}.callgrind")
    argv = callgrind_command(scene, ray_files, accel, out_file)
    stdout = run(argv, log=None)
    summaries = [re.match(r"(\d+) rays, (\d+) hits, (\d+) occluded", line)
                 for line in stdout.splitlines()]
    summaries = [m for m in summaries if m]
    # The first dump ends at the first entry into trace_all: loading and build only.
    costs = [trace_all_cost(path) for path in dump_files(out_file)[1:]]
    if len(summaries) != len(ray_files) or len(costs) != len(ray_files) or None in costs:
        sys.exit(f"count_instructions.py: unexpected callgrind output for {accel}:\n{stdout}")
    return argv, costs, summaries


def placeholder(argv, work):
    return [a.replace(work, WORK) for a in argv]


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scene", help="glTF scene (path relative to the repository root) or "
                                      "'default'")
    parser.add_argument("--rays", type=int, default=10000,
                        help="rays of each kind (default 10000)")
    parser.add_argument("--accel", default=",".join(ACCELS),
                        help=f"structures, comma-separated, each a name or a variant as "
                             f"`rebraid bench --accel` takes it, e.g. flat:robust=1 "
                             f"(default {','.join(ACCELS)})")
    parser.add_argument("--jobs", type=int, default=2,
                        help="callgrind processes at once (default 2)")
    args = parser.parse_args()
    accels = args.accel.split(",")
    # A variant (NAME:KEY=VALUE...) names its structure first; trace_rays checks the rest.
    unknown = [a for a in accels if a.split(":")[0] not in ACCELS]
    if unknown:
        parser.error(f"--accel: unknown structure {unknown[0]!r}: choose from {', '.join(ACCELS)}")
    if args.rays < 1 or args.jobs < 1:
        parser.error("--rays and --jobs must be at least 1")
    for tool in ("valgrind", "callgrind_annotate"):
        if not shutil.which(tool):
            sys.exit(f"count_instructions.py: {tool} is missing (apt-get install valgrind)")
    for binary in (BINARY, TRACER):
        if not os.path.exists(repo_path(binary)):
            sys.exit(f"count_instructions.py: {binary} is missing: build the targets "
                     "rebraid_cli and trace_rays first")

    work = tempfile.mkdtemp(prefix="rebraid-instructions-")
    try:
        # The rays do not depend on the structure: bench makes them with Embree's instanced
        # scene; twolevel is the structure cheapest to build beside it.
        ray_command = [BINARY, "bench", args.scene, "--accel", "twolevel", "--rays",
                       str(args.rays), "--repetitions", "1", "--threads", "1", "--json",
                       "--save-rays", work]
        run(ray_command, log=None)
        stem = scene_name(args.scene)
        ray_files = [os.path.join(work, f"{stem}.{kind}.rays") for kind in KINDS]
        ray_counts = []
        for path in ray_files:
            with open(path) as f:
                ray_counts.append(sum(1 for line in f if line.strip()))
        with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
            futures = {accel: pool.submit(count_structure, args.scene, ray_files, accel, work)
                       for accel in accels}
            counted = {accel: future.result() for accel, future in futures.items()}
        valgrind = subprocess.run(["valgrind", "--version"], capture_output=True,
                                  text=True).stdout.strip()
        structures = []
        for accel in accels:
            argv, costs, summaries = counted[accel]
            row = {"accel": accel}
            for kind, cost, rays, summary in zip(KINDS, costs, ray_counts, summaries):
                row[f"instructions_per_{kind}_ray"] = round(cost / rays, 1)
            for kind, cost, summary in zip(KINDS, costs, summaries):
                row[f"instructions_{kind}"] = cost
                row[f"hits_{kind}"] = int(summary.group(2))
                row[f"occluded_{kind}"] = int(summary.group(3))
            row["command"] = placeholder(argv, work)
            structures.append(row)
        result = {
            "scene": stem,
            "rays_primary": ray_counts[0],
            "rays_diffuse": ray_counts[1],
            "counted": "closest hit and occlusion of every ray (trace_all), callgrind Ir",
            "valgrind": valgrind,
            "ray_command": placeholder(ray_command, work),
            "structures": structures,
        }
        json.dump(result, sys.stdout, indent=1)
        print()
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
