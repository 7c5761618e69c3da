"""Code shared by the benchmark scripts of bench/: running `rebraid` from the repository
root, describing the machine and the commit, reading result files, medians.

Python 3.11 standard library only.
"""
import glob
import json
import os
import platform
import re
import subprocess
import sys

BENCH_DIR = os.path.dirname(os.path.abspath(__file__))
REPO_ROOT = os.path.dirname(BENCH_DIR)
# Paths are given relative to the repository root: commands run from there and are recorded so.
BINARY = "build/examples/rebraid"
# The tracing program that bench/tools/count_instructions.py runs under callgrind.
TRACER = "build/bench/trace_rays"
SHARED_SCENES = "../shared/scenes"
RESULTS_DIR = "bench/results"

# The structures `rebraid bench` builds by default, and the paper's rules as a variant (extent
# opening, transformed node boxes; plain `rebraid` adds the sah opening and vertex bounds).
DEFAULT_ACCELS = ["embree-flat", "embree-instanced", "flat", "twolevel", "rebraid"]
PAPER = "rebraid:opening=extent:bref-bounds=box"


def repo_path(path):
    """An absolute path for a path given relative to the repository root."""
    return path if os.path.isabs(path) else os.path.join(REPO_ROOT, path)


def relative_to_repo(path):
    """`path` relative to the repository root (how commands are recorded)."""
    return os.path.relpath(os.path.abspath(path), REPO_ROOT)


def run_process(argv, env=None, log=sys.stderr):
    """Runs `argv` (paths relative to the repository root) from the repository root, in the
    environment `env` (None: this process's), and returns the finished process with its output;
    exits with that output when it fails."""
    if log:
        print("$ " + " ".join(argv), file=log, flush=True)
    result = subprocess.run(argv, cwd=REPO_ROOT, check=False, capture_output=True, text=True,
                            env=env)
    if result.returncode != 0:
        sys.exit(f"command failed ({result.returncode}): {' '.join(argv)}\n"
                 f"{result.stdout}{result.stderr}")
    return result


def run(argv, log=sys.stderr):
    """Runs `argv` as run_process() does and returns its standard output."""
    return run_process(argv, log=log).stdout


def run_json(argv, log=sys.stderr):
    """Runs `argv` as run() does and returns the JSON it prints on standard output."""
    return json.loads(run(argv, log))


def bench(scene, accels, rays, repetitions, extra=(), binary=BINARY, log=sys.stderr):
    """One `rebraid bench SCENE --json` process: its rows, one per structure."""
    argv = [binary, "bench", scene, "--accel", ",".join(accels), "--rays", str(rays),
            "--repetitions", str(repetitions), "--json", *extra]
    return run_json(argv, log)


def scene_name(path):
    """The short name of a scene argument: 'default' or the file name without extension."""
    return os.path.splitext(os.path.basename(path))[0]


def median(values):
    """The median of the values that are not None, or None when there are none."""
    ordered = sorted(v for v in values if v is not None)
    if not ordered:
        return None
    middle = len(ordered) // 2
    return ordered[middle] if len(ordered) % 2 else 0.5 * (ordered[middle - 1] + ordered[middle])


def _git(*args):
    result = subprocess.run(["git", *args], cwd=REPO_ROOT, capture_output=True, text=True)
    return result.stdout.strip() if result.returncode == 0 else None


def commit_info():
    """The commit of the working tree and whether tracked files differ from it, leaving out
    the collection's own outputs (bench/results/, bench/RESULTS*): results written by a
    collection that has not been committed yet do not change what is measured."""
    head = _git("rev-parse", "HEAD")
    status = _git("status", "--porcelain", "--untracked-files=no", "--", ".",
                  ":(exclude)bench/results", ":(exclude)bench/RESULTS*")
    return {"commit": head, "dirty": bool(status)} if head else {"commit": None, "dirty": None}


def _read(path):
    try:
        with open(path) as f:
            return f.read()
    except OSError:
        return ""


def _library_version(binary, stem):
    """The version in the file name of the shared library `stem` that `binary` loads, from ldd
    and the library's resolved name (e.g. libembree3.so.3.13.5 -> 3.13.5)."""
    try:
        out = subprocess.run(["ldd", repo_path(binary)], capture_output=True, text=True).stdout
    except OSError:
        return None
    for line in out.splitlines():
        match = re.match(rf"\s*({re.escape(stem)}\.so[.\d]*)\s+=>\s+(\S+)", line)
        if match:
            resolved = os.path.basename(os.path.realpath(match.group(2)))
            version = re.search(r"\.so\.([\d.]+)$", resolved)
            return version.group(1) if version else resolved
    return None


def _build_info():
    """Compiler and build type of build/ from its CMakeCache.txt."""
    cache = _read(repo_path("build/CMakeCache.txt"))
    entries = dict(re.findall(r"^(CMAKE_[A-Z_]+):[A-Z]+=(.*)$", cache, re.MULTILINE))
    info = {"build_type": entries.get("CMAKE_BUILD_TYPE") or None}
    compiler = entries.get("CMAKE_CXX_COMPILER")
    if compiler:
        try:
            first = subprocess.run([compiler, "--version"], capture_output=True,
                                   text=True).stdout.splitlines()
            info["compiler"] = first[0].strip() if first else None
        except OSError:
            info["compiler"] = None
    build_type = (info["build_type"] or "").upper()
    flags = " ".join(x for x in (entries.get("CMAKE_CXX_FLAGS", ""),
                                 entries.get(f"CMAKE_CXX_FLAGS_{build_type}", "")) if x)
    info["cxx_flags"] = flags or None
    return info


def machine_info(binary=BINARY):
    """CPU, cores, memory, kernel and the libraries the benchmark binary loads."""
    cpuinfo = _read("/proc/cpuinfo")
    model = re.search(r"^model name\s*:\s*(.*)$", cpuinfo, re.MULTILINE)
    flags = re.search(r"^flags\s*:\s*(.*)$", cpuinfo, re.MULTILINE)
    memory = re.search(r"^MemTotal:\s*(\d+)\s*kB", _read("/proc/meminfo"), re.MULTILINE)
    family = re.search(r"^cpu family\s*:\s*(\d+)$", cpuinfo, re.MULTILINE)
    model_number = re.search(r"^model\s*:\s*(\d+)$", cpuinfo, re.MULTILINE)
    uname = platform.uname()
    flag_set = set(flags.group(1).split()) if flags else set()
    return {
        "cpu": model.group(1).strip() if model else platform.processor() or None,
        # A virtual machine's model name may not tell one generation from another (both
        # "AMD EPYC"); family and model do.
        "cpu_family_model": (f"family {family.group(1)}, model {model_number.group(1)}"
                             if family and model_number else None),
        "logical_cores": os.cpu_count(),
        "simd": [f for f in ("sse4_2", "avx", "avx2", "avx512f") if f in flag_set],
        "memory_gib": round(int(memory.group(1)) / 1024 ** 2, 1) if memory else None,
        "kernel": f"{uname.system} {uname.release}",
        "embree": _library_version(binary, "libembree3"),
        "tbb": _library_version(binary, "libtbb"),
        **_build_info(),
    }


def load_average():
    """The 1-minute load average (None where /proc/loadavg is missing)."""
    text = _read("/proc/loadavg").split()
    return float(text[0]) if text else None


def load_results(directory):
    """Every result file under `directory` (recursively), sorted by suite, name and round."""
    results = []
    for path in sorted(glob.glob(os.path.join(directory, "**", "*.json"), recursive=True)):
        with open(path) as f:
            data = json.load(f)
        if isinstance(data, dict) and "output" in data and "name" in data:
            results.append(data)
    results.sort(key=lambda r: (r.get("suite", ""), r["name"], r.get("round", 0)))
    return results
