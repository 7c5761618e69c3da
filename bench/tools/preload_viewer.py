#!/usr/bin/env python3
"""Embree's own viewer (Debian's embree-tools) with and without librebraid_preload.so, on one
glTF scene exported with `rebraid export --embree-xml`; prints one JSON object.

  python3 bench/tools/preload_viewer.py SCENE.glb [--runs N] [--build DIR]

Three configurations take turns, N times (default 3), on the same camera and image size
(`viewer -i scene.xml -c camera.cfg --size 640 360 --benchmark 2 8`, which prints
BENCHMARK_RENDER_MRAYPS_AVG):

  embree_instanced  --instancing geometry (one Embree instance per instance, shared meshes)
  embree_flat       --instancing none (Embree's viewer flattens the instances into one scene)
  preload           --instancing geometry under LD_PRELOAD=DIR/lib/librebraid_preload.so

and reports each one's runs and median Mrays/s, with the cost of the commit beside Embree's:
rebraid's build of the instanced scene (the preload's REBRAID_PRELOAD_LOG line) and the time
the viewer takes to create and commit its Embree objects (its --verbose 1 timeline), each
from one small render. Run it on an otherwise idle machine: the viewer uses every core.

Python 3.11 standard library only; needs the `viewer` program on PATH.
"""
import argparse
import json
import os
import re
import shutil
import statistics
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from results_io import repo_path, run_process  # noqa: E402

CONFIGS = ["embree_instanced", "embree_flat", "preload"]


def run(argv, env=None):
    return run_process(argv, env=env, log=None)


def environment(preload=None, log=False):
    env = dict(os.environ)
    env.pop("LD_PRELOAD", None)
    if preload:
        env["LD_PRELOAD"] = preload
    if log:
        env["REBRAID_PRELOAD_LOG"] = "1"
    return env


def mrays(output):
    match = re.search(r"^BENCHMARK_RENDER_MRAYPS_AVG\s+([0-9.eE+-]+)\s*$", output, re.MULTILINE)
    if not match:
        sys.exit("preload_viewer.py: the viewer printed no BENCHMARK_RENDER_MRAYPS_AVG")
    return float(match.group(1))


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scene", help="a .glb or .gltf scene")
    parser.add_argument("--runs", type=int, default=3, help="runs of each configuration")
    parser.add_argument("--build", default="build", help="build folder (default build)")
    args = parser.parse_args()
    if args.runs < 1:
        parser.error("--runs must be at least 1")
    viewer = shutil.which("viewer")
    if not viewer:
        sys.exit("preload_viewer.py: Embree's `viewer` is missing (Debian: embree-tools)")
    build = repo_path(args.build)
    binary = os.path.join(build, "examples", "rebraid")
    preload = os.path.join(build, "lib", "librebraid_preload.so")
    for path in (binary, preload):
        if not os.path.exists(path):
            sys.exit(f"preload_viewer.py: {path} is missing: build the project first")

    work = tempfile.mkdtemp(prefix="rebraid-viewer-")
    try:
        run([binary, "export", os.path.abspath(args.scene), "--embree-xml", work])
        scene = [viewer, "-i", os.path.join(work, "scene.xml"),
                 "-c", os.path.join(work, "camera.cfg")]
        timed = ["--size", "640", "360", "--benchmark", "2", "8"]
        commands = {
            "embree_instanced": (scene + ["--instancing", "geometry"] + timed, None),
            "embree_flat": (scene + ["--instancing", "none"] + timed, None),
            "preload": (scene + ["--instancing", "geometry"] + timed, preload),
        }
        runs = {config: [] for config in CONFIGS}
        for _ in range(args.runs):
            for config in CONFIGS:
                argv, library = commands[config]
                runs[config].append(mrays(run(argv, environment(library)).stdout))

        small = scene + ["--instancing", "geometry", "--size", "64", "36",
                         "-o", os.path.join(work, "image.ppm")]
        log = run(small, environment(preload, log=True)).stderr
        served = re.search(r"rebraid serves it \(build ([0-9.]+) ms, (\d+) instances, "
                           r"(\d+) triangles\)", log)
        timeline = run(small + ["--verbose", "1"], environment()).stdout
        stamps = dict((m.group(2), float(m.group(1))) for m in re.finditer(
            r"^\[\s*([0-9.]+)s,.*\]\s+(.*?) done\s*$", timeline, re.MULTILINE))
        objects_ms = None
        if "creating Embree objects" in stamps and "creating ISPC compatible scene" in stamps:
            objects_ms = round(1000 * (stamps["creating Embree objects"]
                                       - stamps["creating ISPC compatible scene"]), 1)
    finally:
        shutil.rmtree(work, ignore_errors=True)

    result = {
        "scene": os.path.splitext(os.path.basename(args.scene))[0],
        "image": [640, 360],
        "runs": runs,
        "served": served is not None,
        "not_served_because": None if served else (log.strip().splitlines() or [None])[-1],
        "rebraid_build_ms": float(served.group(1)) if served else None,
        "instances": int(served.group(2)) if served else None,
        "triangles": int(served.group(3)) if served else None,
        "embree_objects_ms": objects_ms,
    }
    for config in CONFIGS:
        result[f"{config}_mrays"] = statistics.median(runs[config])
    json.dump(result, sys.stdout, indent=1)
    print()


if __name__ == "__main__":
    main()
