#!/usr/bin/env python3
"""Two versions of the traversal kernels in one program, on the same rays: an earlier revision's
and the working tree's, taking turns, so that a change worth a few percent is not lost in the
noise between processes.

  python3 bench/tools/kernel_ab.py REVISION SCENE RAYS ACCEL [--rounds N] [--located]
                                   [--build DIR] [--isa avx2|avx512]
                                   [--current-flags FLAGS]

REVISION is a git revision; SCENE a glTF file or `default`; RAYS a ray file (`rebraid bench
--save-rays`, `rebraid rays`); ACCEL one of the project's structures as `rebraid bench --accel`
names it (flat, twolevel, rebraid and their variants). The tool exports REVISION's rebraid/
headers into a temporary folder with their SIMD namespace renamed, compiles
bench/tools/kernel_ab/kernels.cpp against them and against the working tree, links both with
the driver and the libraries of the build folder (default build/, built first: the structure
is built by the working tree's library), and runs it: N rounds (default 21, the first a
warm-up) on one thread, each tracing every ray's closest hit with both versions in turn. It
prints the driver's JSON: both versions' median Mrays/s, the median of the rounds' ratios
(current over earlier) with its quartiles, and whether both found the same hits.

The two copies sit at different addresses, which alone moves the ratio by up to about 1 %
(the same revision against itself measured 0.99): read smaller differences as none.

Only revisions whose structures have the working tree's layout can be compared (the earlier
kernels read the structure the current library built): not across a change of WideNode, the
leaf rows or the top level's records. --isa picks the instruction set the kernels are compiled
for (default: avx512 where the CPU has it, as the library's kernel levels choose);
--current-flags adds compiler flags to the working tree's copy only, so that a code-layout or
optimisation flag is measured against the same source without it.

Python 3.11 standard library only; needs git and the C++ compiler the build uses.
"""
import argparse
import os
import re
import shlex
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from results_io import repo_path  # noqa: E402

SOURCES = os.path.join("bench", "tools", "kernel_ab")
ISA_FLAGS = {"avx2": ["-mavx2", "-mfma"],
             "avx512": ["-mavx2", "-mfma", "-mavx512f", "-mavx512vl", "-mavx512bw",
                        "-mavx512dq"]}


def cpu_has_avx512():
    try:
        with open("/proc/cpuinfo") as info:
            flags = info.read()
    except OSError:
        return False
    return all(re.search(r"\b" + flag + r"\b", flags)
               for flag in ("avx512f", "avx512vl", "avx512bw", "avx512dq"))


def run(argv, **kwargs):
    result = subprocess.run(argv, capture_output=True, text=True, **kwargs)
    if result.returncode != 0:
        sys.exit(f"kernel_ab.py: {shlex.join(argv)} failed:\n{result.stderr}")
    return result.stdout


def link_line(build):
    """The compiler, the object of accel_factory.cpp and the libraries trace_rays links."""
    run(["ninja", "-C", build, "bench/trace_rays"])
    commands = run(["ninja", "-C", build, "-t", "commands", "bench/trace_rays"]).splitlines()
    link = next(line for line in reversed(commands) if "-o bench/trace_rays" in line)
    words = shlex.split(link.split("&&")[1])
    compiler = words[0]
    factory = next(w for w in words if w.endswith("accel_factory.cpp.o"))
    libraries = words[words.index("bench/trace_rays") + 1:]
    return compiler, os.path.join(build, factory), [
        w if os.path.isabs(w) else os.path.join(build, w) for w in libraries]


def export_earlier(revision, folder):
    archive = subprocess.run(["git", "archive", "--format=tar", revision, "rebraid"],
                             cwd=repo_path("."), capture_output=True)
    if archive.returncode != 0:
        sys.exit(f"kernel_ab.py: git archive {revision} failed:\n{archive.stderr.decode()}")
    subprocess.run(["tar", "-x", "-C", folder], input=archive.stdout, check=True)
    config = os.path.join(folder, "rebraid", "core", "simd_config.h")
    with open(config) as f:
        text = f.read()
    renamed = re.sub(r"(#define REBRAID_SIMD_NAMESPACE simd_\w+)", r"\1_earlier", text)
    if renamed == text:
        sys.exit("kernel_ab.py: no REBRAID_SIMD_NAMESPACE in the revision's simd_config.h")
    with open(config, "w") as f:
        f.write(renamed)


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("revision")
    parser.add_argument("scene")
    parser.add_argument("rays")
    parser.add_argument("accel")
    parser.add_argument("--rounds", type=int, default=21)
    parser.add_argument("--located", action="store_true",
                        help="the located query (the Embree glue's) instead of the plain one")
    parser.add_argument("--build", default=repo_path("build"))
    parser.add_argument("--current-flags", default="",
                        help="extra compiler flags for the working tree's kernels only "
                             "(e.g. to measure a code-layout flag against the same source)")
    parser.add_argument("--isa", choices=sorted(ISA_FLAGS),
                        default="avx512" if cpu_has_avx512() else "avx2")
    args = parser.parse_args()
    compiler, factory, libraries = link_line(args.build)
    flags = ["-O3", "-DNDEBUG", "-std=c++20"] + ISA_FLAGS[args.isa]
    sources = repo_path(SOURCES)
    with tempfile.TemporaryDirectory() as work:
        earlier = os.path.join(work, "earlier")
        os.makedirs(earlier)
        export_earlier(args.revision, earlier)
        objects = []
        for name, include in (("earlier", earlier), ("current", repo_path("."))):
            objects.append(os.path.join(work, name + ".o"))
            extra = shlex.split(args.current_flags) if name == "current" else []
            run([compiler, *flags, *extra, "-I", include, f"-DKERNEL_AB_RUN=run_{name}", "-c",
                 os.path.join(sources, "kernels.cpp"), "-o", objects[-1]])
        objects.append(os.path.join(work, "driver.o"))
        run([compiler, "-O2", "-std=c++20", "-I", repo_path(os.path.join("examples", "cli")),
             "-I", repo_path("."), "-c", os.path.join(sources, "driver.cpp"), "-o", objects[-1]])
        binary = os.path.join(work, "kernel_ab")
        run([compiler, *objects, factory, "-o", binary, *libraries])
        argv = [binary, args.scene, args.rays, args.accel, str(args.rounds)]
        if args.located:
            argv.append("located")
        sys.stdout.write(run(argv))


if __name__ == "__main__":
    main()
