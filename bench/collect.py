#!/usr/bin/env python3
"""Run the benchmarks and write their raw results to bench/results/ (bench/report.py turns
them into bench/RESULTS.md).

  python3 bench/collect.py                       every suite, 5 rounds, into bench/results/
  python3 bench/collect.py --suite scenes        one suite (repeatable)
  python3 bench/collect.py --quick --out DIR     tiny ray counts and one round, to test the
                                                 pipeline (without --out: a new temporary folder)

Suites (every command runs from the repository root):

  structures `rebraid stats SCENE --accel A --json` for flat, twolevel and rebraid on the
             default scene and every shared scene: SAH and structure_hash (deterministic, so
             one round whatever --rounds says)
  scenes     `rebraid bench SCENE --json` for the built-in default scene and every
             ../shared/scenes/*.glb, with the default structures (embree-flat,
             embree-instanced, flat, twolevel, rebraid) and the paper's rules
             (rebraid:opening=extent:bref-bounds=box)
  generated  the same for `rebraid generate KIND` (trees, crown, powerplant, city; the kinds'
             defaults), written to a temporary folder first
  forests    `rebraid stats FILE --accel A --json` for twolevel and rebraid on
             `rebraid generate trees --instances N` at 100,000 and 1,000,000 instances (255 M
             and 2.55 G instanced triangles): build times, SAH, memory and peak RSS at scale;
             and `rebraid bench FILE --accel embree-instanced,twolevel,rebraid --json` on the
             same files: Mrays/s at scale (--quick: 1,000 instances)
  animate    `rebraid animate --json`: the built-in twisting object in the default scene, and
             each animated shared scene (per ../shared/scenes/MANIFEST.md) as --dynamic in
             ../shared/scenes/cg57_cruiser.glb
  instructions
             `python3 bench/tools/count_instructions.py SCENE`: exact instructions per primary
             and per diffuse ray (closest hit + occluded, callgrind) of embree-flat,
             embree-instanced, flat, twolevel and rebraid on 10,000 rays of each kind, for the
             default scene, every shared scene and the generated kinds (deterministic, so one
             round; needs valgrind and build/bench/trace_rays, without which a run of every
             suite skips it; --quick: the default scene alone on 200 rays)
  preload    `python3 bench/tools/preload_viewer.py SCENE --runs 3` for every shared scene:
             Embree's own viewer (embree-tools) on the scene exported to Embree's XML,
             instanced and flattened, and instanced under build/lib/librebraid_preload.so,
             taking turns (Mrays/s of its 640x360 camera rays), with rebraid's build time
             beside Embree's commit (needs `viewer`, without which a run of every suite skips
             it; --quick: one run on the first shared scene)
  dropin     `python3 bench/tools/dropin_grid.py --run TMP/dropin`: examples/dropin built
             against the installed package (once, by `--prepare`), its `--bench`: a grid of
             instanced torus knots and the same grid flattened, traced by rtcIntersect1,
             EmbreeAccel::intersect1 and the user-geometry scene (one thread)

A round runs every command of a suite once, each as its own process on the same rays and
seeds; --rounds K repeats that K times (report.py prints medians over the rounds). Each
command's result is one JSON file, SUITE/NAME.rROUND.json, holding the command (argv, paths
relative to the repository root), the commit, the machine, the date, the round and the parsed
output. Collecting a suite first deletes that suite's earlier files in the output folder.

Measured time on a 2-core machine (AMD Zen 5, 24 GiB), idle, 5 rounds: structures 13 s,
scenes 1.8 min, generated 3.5 min (mostly trees and powerplant), forests 4.3 min (half of it
tracing the million-instance forest), animate 11 min (20 frames of 640x360 primary and diffuse
rays for 15 methods, 4 runs): 21 minutes for these five. Run it on an otherwise idle
machine: the builds and the rays use every core. The `instructions` suite counts rather than
times, so any machine load leaves its results as they are (it only runs longer): one round
took 9 minutes on the idle machine (14 on a shared one; most of it the builds of trees,
powerplant and crown, whose millions of triangles valgrind emulates slowly), which brings the
full default collection to about 30 minutes; its --quick part (the default scene) adds about
1.3 minutes. `preload` takes about 20 s a round and `dropin` about 5 s a round (plus half a
minute, once, to install the package and build the example).
"""
import argparse
import datetime
import glob
import json
import os
import re
import shutil
import sys
import tempfile
import time

from results_io import (BINARY, DEFAULT_ACCELS, PAPER, RESULTS_DIR, SHARED_SCENES, TRACER,
                        commit_info, load_average, machine_info, relative_to_repo, repo_path,
                        run, run_json, scene_name)

SUITES = ["structures", "scenes", "generated", "forests", "animate", "instructions", "preload",
          "dropin"]
# The structures whose SAH and structure_hash the `structures` suite records.
STRUCTURE_ACCELS = ["flat", "twolevel", "rebraid"]
GENERATED_KINDS = ["trees", "crown", "powerplant", "city"]
# The structures the `forests` suite builds over the large generated forests.
FOREST_ACCELS = ["twolevel", "rebraid"]
# The structures the `forests` suite traces rays through on the same forests.
FOREST_BENCH_ACCELS = ["embree-instanced", "twolevel", "rebraid"]
ANIMATE_STATIC = f"{SHARED_SCENES}/cg57_cruiser.glb"
# Used when the MANIFEST cannot be read: the shared scenes it lists with an animation.
ANIMATED_FALLBACK = ["brainstem", "motion_capture_rom", "animated_morph_cube"]
# Stands for the temporary folder of the generated scenes in recorded commands.
TMP = "TMP"

# Ray counts (230400 = a 640x360 image; as many diffuse rays), timed repetitions per process
# and animation frames: a full collection (all suites, 5 rounds) takes ~45 minutes on 2 cores.
# --quick only checks that the pipeline runs.
# `instructions` counts 10,000 rays of each kind (valgrind is ~50x slower; --quick: the default
# scene alone).
FULL = {"rays": 230400, "repetitions": 5, "frames": 20, "animate": [],
        "instruction_rays": 10000, "instruction_scenes": "all",
        "forest_instances": [100000, 1000000], "viewer_runs": 3, "viewer_scenes": "all"}
QUICK = {"rays": 2000, "repetitions": 1, "frames": 2,
         "animate": ["--width", "64", "--height", "36"],
         "instruction_rays": 200, "instruction_scenes": "default",
         "forest_instances": [1000], "viewer_runs": 1, "viewer_scenes": "first"}
COUNT_INSTRUCTIONS = "bench/tools/count_instructions.py"
PRELOAD_VIEWER = "bench/tools/preload_viewer.py"
PRELOAD_LIBRARY = "build/lib/librebraid_preload.so"
DROPIN_GRID = "bench/tools/dropin_grid.py"


def shared_scenes():
    return sorted(relative_to_repo(p) for p in
                  glob.glob(os.path.join(repo_path(SHARED_SCENES), "*.glb")))


def animated_shared_scenes():
    """Shared scenes whose MANIFEST row names an animation (its 'animation' column is not
    'none')."""
    names = []
    try:
        with open(repo_path(f"{SHARED_SCENES}/MANIFEST.md")) as f:
            lines = f.read().splitlines()
    except OSError:
        lines = []
    header = None
    for line in lines:
        if not line.startswith("|"):
            header = None
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if header is None:
            header = [c.lower() for c in cells]
            continue
        if set("".join(cells)) <= set("-: ") or "file" not in header or "animation" not in header:
            continue
        file, animation = cells[header.index("file")], cells[header.index("animation")]
        if file.endswith(".glb") and animation and animation.lower() != "none":
            names.append(scene_name(file))
    names = names or ANIMATED_FALLBACK
    return [f"{SHARED_SCENES}/{n}.glb" for n in names
            if os.path.exists(repo_path(f"{SHARED_SCENES}/{n}.glb"))]


def bench_command(scene, settings, threads):
    argv = [BINARY, "bench", scene, "--accel", ",".join(DEFAULT_ACCELS + [PAPER]),
            "--rays", str(settings["rays"]), "--repetitions", str(settings["repetitions"]), "--json"]
    return argv + (["--threads", str(threads)] if threads is not None else [])


def animate_command(static, dynamic, settings, threads):
    argv = [BINARY, "animate"]
    if static:
        argv += ["--static", static]
    if dynamic:
        argv += ["--dynamic", dynamic]
    argv += ["--frames", str(settings["frames"]), *settings["animate"], "--json"]
    return argv + (["--threads", str(threads)] if threads is not None else [])


def generate_command(kind, threads):
    argv = [BINARY, "generate", kind, "-o", f"{TMP}/{kind}.glb"]
    return argv + (["--threads", str(threads)] if threads is not None else [])


def jobs_of(suite, settings, threads):
    """The suite's (name, argv, setup argvs) triples; argv may name files under TMP/."""
    if suite == "structures":
        jobs = []
        for scene in ["default"] + shared_scenes():
            for accel in STRUCTURE_ACCELS:
                argv = [BINARY, "stats", scene, "--accel", accel, "--json"]
                argv += ["--threads", str(threads)] if threads is not None else []
                jobs.append((f"{scene_name(scene)}-{accel}", argv, []))
        return jobs
    if suite == "scenes":
        return [(scene_name(s), bench_command(s, settings, threads), [])
                for s in ["default"] + shared_scenes()]
    if suite == "generated":
        return [(kind, bench_command(f"{TMP}/{kind}.glb", settings, threads),
                 [generate_command(kind, threads)]) for kind in GENERATED_KINDS]
    if suite == "forests":
        jobs = []
        for count in settings["forest_instances"]:
            forest = f"trees-{count}"
            generate = [BINARY, "generate", "trees", "--instances", str(count),
                        "-o", f"{TMP}/{forest}.glb"]
            generate += ["--threads", str(threads)] if threads is not None else []
            for index, accel in enumerate(FOREST_ACCELS):
                argv = [BINARY, "stats", f"{TMP}/{forest}.glb", "--accel", accel, "--json"]
                argv += ["--threads", str(threads)] if threads is not None else []
                # One generation serves both structures.
                jobs.append((f"{forest}-{accel}", argv, [generate] if index == 0 else []))
            argv = [BINARY, "bench", f"{TMP}/{forest}.glb", "--accel",
                    ",".join(FOREST_BENCH_ACCELS), "--rays", str(settings["rays"]),
                    "--repetitions", str(settings["repetitions"]), "--json"]
            argv += ["--threads", str(threads)] if threads is not None else []
            jobs.append((f"{forest}-bench", argv, []))
        return jobs
    if suite == "instructions":
        def count(scene):
            return ["python3", COUNT_INSTRUCTIONS, scene, "--rays",
                    str(settings["instruction_rays"]), "--jobs", "2"]
        jobs = [("default", count("default"), [])]
        if settings["instruction_scenes"] == "all":
            jobs += [(scene_name(s), count(s), []) for s in shared_scenes()]
            jobs += [(kind, count(f"{TMP}/{kind}.glb"), [generate_command(kind, threads)])
                     for kind in GENERATED_KINDS]
        return jobs
    if suite == "preload":
        scenes = shared_scenes()
        if settings["viewer_scenes"] == "first":
            scenes = scenes[:1]
        return [(scene_name(s), ["python3", PRELOAD_VIEWER, s, "--runs",
                                 str(settings["viewer_runs"])], []) for s in scenes]
    if suite == "dropin":
        return [("grid", ["python3", DROPIN_GRID, "--run", f"{TMP}/dropin"],
                 [["python3", DROPIN_GRID, "--prepare", f"{TMP}/dropin"]])]
    if suite == "animate":
        jobs = [("default", animate_command(None, None, settings, threads), [])]
        static = ANIMATE_STATIC if os.path.exists(repo_path(ANIMATE_STATIC)) else None
        for dynamic in animated_shared_scenes():
            name = f"{scene_name(dynamic)}-in-{scene_name(static) if static else 'default'}"
            jobs.append((name, animate_command(static, dynamic, settings, threads), []))
        return jobs
    raise ValueError(suite)


def substitute(argv, tmp):
    return [a.replace(f"{TMP}/", tmp + "/", 1) if a.startswith(f"{TMP}/") else a for a in argv]


def unsubstitute(value, tmp):
    """`value` (parsed JSON) with the temporary folder written as TMP again, as the commands
    are recorded."""
    if isinstance(value, str):
        return value.replace(tmp + "/", f"{TMP}/")
    if isinstance(value, list):
        return [unsubstitute(v, tmp) for v in value]
    if isinstance(value, dict):
        return {k: unsubstitute(v, tmp) for k, v in value.items()}
    return value


def utc_now():
    return datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--suite", action="append", choices=SUITES,
                        help="suite to run (repeatable; default: all)")
    parser.add_argument("--only", action="append", metavar="NAME",
                        help="run only the commands of this name in the suites (repeatable), "
                             "e.g. --suite scenes --only default")
    parser.add_argument("--rounds", type=int, help="rounds per command (default 5; --quick: 1)")
    parser.add_argument("--quick", action="store_true",
                        help="tiny ray counts and one round, to test the pipeline; writes to "
                             "--out, or to a new temporary folder")
    parser.add_argument("--out", help=f"output folder (default {RESULTS_DIR}/)")
    parser.add_argument("--threads", type=int,
                        help="pass --threads N to every command (default: all cores)")
    args = parser.parse_args()

    settings = QUICK if args.quick else FULL
    rounds = args.rounds if args.rounds is not None else (1 if args.quick else 5)
    if rounds < 1:
        parser.error("--rounds must be at least 1")
    if args.out:
        out = os.path.abspath(args.out)
    elif args.quick:
        out = tempfile.mkdtemp(prefix="rebraid-results-")
    else:
        out = repo_path(RESULTS_DIR)
    if not os.path.exists(repo_path(BINARY)):
        sys.exit(f"collect.py: {BINARY} is missing: build the project first")
    suites = args.suite or SUITES
    # Suites that need tools beyond the build: without them a run of every suite skips
    # them, and asking for one by name fails.
    requirements = {
        "preload": (shutil.which("viewer") and os.path.exists(repo_path(PRELOAD_LIBRARY)),
                    f"Embree's viewer (embree-tools) or {PRELOAD_LIBRARY} is missing"),
        "instructions": (shutil.which("valgrind") and os.path.exists(repo_path(TRACER)),
                         f"valgrind or {TRACER} (build the target trace_rays) is missing"),
    }
    for suite, (is_met, missing) in requirements.items():
        if suite not in suites or is_met:
            continue
        if args.suite:
            sys.exit(f"collect.py: suite {suite}: {missing}")
        print(f"collect.py: skipping suite {suite}: {missing}", file=sys.stderr)
        suites = [s for s in suites if s != suite]

    # The command as recorded: the options that shape the results, paths relative to the
    # repository root (an output folder outside it is not recorded).
    collect_argv = ["python3", "bench/collect.py"]
    if args.quick:
        collect_argv.append("--quick")
    collect_argv += ["--rounds", str(rounds)]
    if args.threads is not None:
        collect_argv += ["--threads", str(args.threads)]
    for name in args.only or []:
        collect_argv += ["--only", name]
    if args.out and not relative_to_repo(out).startswith(".."):
        collect_argv += ["--out", relative_to_repo(out)]
    machine = machine_info()
    commit = commit_info()
    print(f"collect.py: {rounds} round(s) of {', '.join(suites)} into {out}", file=sys.stderr)
    if commit["dirty"]:
        print("collect.py: the working tree differs from the commit (recorded as dirty)",
              file=sys.stderr)

    durations = {}
    tmp = tempfile.mkdtemp(prefix="rebraid-scenes-")
    try:
        for suite in suites:
            jobs = [j for j in jobs_of(suite, settings, args.threads)
                    if not args.only or j[0] in args.only]
            if not jobs:
                continue
            folder = os.path.join(out, suite)
            os.makedirs(folder, exist_ok=True)
            names = {name for name, _, _ in jobs}
            for old in os.listdir(folder):
                match = re.fullmatch(r"(.+)\.r\d+\.json", old)
                if match and match.group(1) in names:
                    os.remove(os.path.join(folder, old))
            start = time.monotonic()
            for _, _, setup in jobs:
                for argv in setup:
                    run(substitute(argv, tmp))
            # Structures and instruction counts are deterministic: one round says all.
            suite_rounds = 1 if suite in ("structures", "instructions") else rounds
            for round_index in range(1, suite_rounds + 1):
                for order, (name, argv, setup) in enumerate(jobs):
                    load = load_average()
                    date = utc_now()
                    job_start = time.monotonic()
                    output = unsubstitute(run_json(substitute(argv, tmp)), tmp)
                    result = {
                        "name": name,
                        "suite": suite,
                        "command": argv,
                        "setup": setup,
                        "order": order,
                        "collect_command": collect_argv[:2] + ["--suite", suite] + collect_argv[2:],
                        "commit": commit["commit"],
                        "dirty": commit["dirty"],
                        "machine": machine,
                        "date": date,
                        "round": round_index,
                        "rounds": rounds,
                        "seconds": round(time.monotonic() - job_start, 2),
                        "load_average_before": load,
                        "output": output,
                    }
                    path = os.path.join(folder, f"{name}.r{round_index}.json")
                    with open(path, "w") as f:
                        json.dump(result, f, indent=1)
                        f.write("\n")
                    print(f"  {suite}/{name} round {round_index}: {result['seconds']:.1f} s",
                          file=sys.stderr, flush=True)
            durations[suite] = time.monotonic() - start
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    for suite, seconds in durations.items():
        print(f"collect.py: {suite}: {seconds:.0f} s for {rounds} round(s) "
              f"({seconds / rounds:.0f} s a round)", file=sys.stderr)
    print(f"collect.py: results in {out}", file=sys.stderr)


if __name__ == "__main__":
    main()
