#!/usr/bin/env python3
"""Write bench/RESULTS.md from the raw results that bench/collect.py wrote to bench/results/.

  python3 bench/report.py                          bench/results/ -> bench/RESULTS.md
  python3 bench/report.py --results DIR --out FILE
  python3 bench/report.py --plots                  also draw figures beside the output file
                                                   (needs matplotlib; without it the report is
                                                   written without figures)

The output depends only on the result files (and the options): the same input gives the same
bytes. Every figure is a median over the rounds; a ratio of two structures is computed in each
round (one process, the same rays) and its median over the rounds is shown.
"""
import argparse
import os
import sys

from results_io import DEFAULT_ACCELS, PAPER, RESULTS_DIR, load_results, median, repo_path

SUITE_ORDER = {"structures": 0, "scenes": 1, "generated": 2, "forests": 3, "animate": 4,
               "instructions": 5, "preload": 6, "dropin": 7}
# Short column names of the structures; any other variant keeps its full name.
LABELS = {PAPER: "paper"}
PROJECT = ["flat", "twolevel", "rebraid", PAPER]
DASH = "-"


# ---------------------------------------------------------------- formatting

def fmt(value, digits=2):
    return DASH if value is None else f"{value:.{digits}f}"


def fmt_ms(value):
    """Milliseconds with precision by magnitude."""
    if value is None:
        return DASH
    return fmt_sig(value)


def fmt_mib(num_bytes):
    """Bytes as MiB, with about three significant digits."""
    return DASH if num_bytes is None else fmt_sig(num_bytes / 2 ** 20)


def fmt_sig(value):
    """A positive quantity with about three significant digits."""
    if value is None:
        return DASH
    for limit, digits in ((100, 0), (10, 1), (1, 2)):
        if value >= limit:
            return f"{value:.{digits}f}"
    return f"{value:.3f}"


def fmt_int(value):
    return DASH if value is None else f"{round(value):,}"


def fmt_ratio(value):
    if value is None:
        return DASH
    return f"{value:.0f}" if value >= 100 else f"{value:.1f}" if value >= 10 else f"{value:.2f}"


def table(header, rows, left=1):
    """A Markdown table; the first `left` columns are aligned left, the others right."""
    lines = ["| " + " | ".join(header) + " |",
             "|" + "|".join("---" if i < left else "--:" for i in range(len(header))) + "|"]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def label(accel):
    return LABELS.get(accel, accel)


def code(argv):
    return " ".join(quote(a) for a in argv)


def quote(arg):
    safe = set("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_./:=,+@%")
    return arg if arg and set(arg) <= safe else "'" + arg.replace("'", "'\\''") + "'"


# ---------------------------------------------------------------- grouping

class Run:
    """The rounds of one command: its result files, in round order."""

    def __init__(self, results):
        self.results = sorted(results, key=lambda r: r.get("round", 0))
        first = self.results[0]
        self.name, self.suite, self.command = first["name"], first.get("suite", ""), first["command"]
        self.order = first.get("order", 0)

    def rows(self, key):
        """Per round, the output rows keyed by `key` ('accel' or 'method')."""
        return [{row[key]: row for row in r["output"]} for r in self.results]

    def names(self, key):
        seen = []
        for rows in self.rows(key):
            seen += [n for n in rows if n not in seen]
        return seen

    def value(self, key, name, field):
        """The median over rounds of row `name`'s `field`."""
        return median([rows[name].get(field) for rows in self.rows(key) if name in rows])

    def ratio(self, key, a, b, field):
        """The median over rounds of a's `field` over b's, each round's from its own output."""
        values = []
        for rows in self.rows(key):
            if a in rows and b in rows:
                x, y = rows[a].get(field), rows[b].get(field)
                if x is not None and y:
                    values.append(x / y)
        return median(values)

    def first(self, key, name, field):
        for rows in self.rows(key):
            if name in rows and rows[name].get(field) is not None:
                return rows[name][field]
        return None


def group_runs(results):
    runs = {}
    for r in results:
        runs.setdefault((r.get("suite", ""), r["name"]), []).append(r)
    return sorted((Run(v) for v in runs.values()),
                  key=lambda run: (SUITE_ORDER.get(run.suite, 9), run.suite, run.order, run.name))


def ordered_accels(runs):
    seen = []
    for run in runs:
        seen += [a for a in run.names("accel") if a not in seen]
    known = [a for a in DEFAULT_ACCELS + [PAPER] if a in seen]
    return known + [a for a in seen if a not in known]


# ---------------------------------------------------------------- sections

def section_setup(results, runs):
    out = ["## Setup\n"]
    machines = {}
    for r in results:
        m = r.get("machine", {})
        key = tuple(sorted((k, str(v)) for k, v in m.items()))
        machines.setdefault(key, (m, set()))[1].add(r.get("suite", ""))
    for m, suites in machines.values():
        simd = ", ".join(s.upper().replace("_", ".") for s in m.get("simd") or [])
        where = f" ({', '.join(sorted(suites))})" if len(machines) > 1 else ""
        cpu = m.get("cpu") or "unknown CPU"
        if m.get("cpu_family_model"):
            cpu += f" ({m['cpu_family_model']})"
        out.append(f"- **Machine{where}:** {cpu}, "
                   f"{m.get('logical_cores', '?')} logical cores"
                   + (f" ({simd})" if simd else "")
                   + f", {m.get('memory_gib', '?')} GiB memory, {m.get('kernel', '?')}.")
        software = []
        if m.get("embree"):
            software.append(f"Embree {m['embree']}")
        if m.get("tbb"):
            software.append(f"oneTBB (libtbb.so.{m['tbb']})")
        if m.get("compiler"):
            software.append(m["compiler"])
        if m.get("build_type"):
            flags = f" `{m['cxx_flags']}`" if m.get("cxx_flags") else ""
            software.append(f"{m['build_type']} build{flags}")
        if software:
            out.append(f"- **Software{where}:** " + ", ".join(software) + ".")
    commits = {}
    for r in results:
        commits.setdefault((r.get("commit"), r.get("dirty")), set()).add(r.get("suite", ""))
    for (commit, dirty), suites in sorted(commits.items(), key=lambda c: str(c[0])):
        where = f" ({', '.join(sorted(suites))})" if len(commits) > 1 else ""
        state = " with uncommitted changes in the working tree" if dirty else ""
        out.append(f"- **Commit{where}:** `{commit or 'unknown'}`{state}.")
    dates = sorted(r["date"] for r in results if r.get("date"))
    if dates:
        span = dates[0] if dates[0] == dates[-1] else f"{dates[0]} to {dates[-1]}"
        out.append(f"- **Collected:** {span} (UTC).")
    rounds = sorted({len(run.results) for run in runs})
    out.append(f"- **Rounds:** {' or '.join(map(str, rounds))} per command, each its own process.")
    loads = [r["load_average_before"] for r in results if r.get("load_average_before") is not None]
    if loads:
        out.append(f"- **Load average** (1 min) before each command: median {median(loads):.2f}, "
                   f"highest {max(loads):.2f}, on {results[0].get('machine', {}).get('logical_cores', '?')}"
                   " logical cores.")
    return "\n".join(out) + "\n"


def section_method(runs):
    threads = sorted({row.get("threads") for run in runs for r in run.results
                      for row in r["output"] if isinstance(row, dict) and row.get("threads")})
    thread_text = (" or ".join(f"{t} thread{'s' if t != 1 else ''}" for t in threads)
                   if threads else "all cores")
    return f"""## How the numbers are measured

- `rebraid bench` builds every structure of one scene in one process and traces the same rays
  through each: primary rays of the auto-framed camera (one per pixel of a 16:9 image) and as
  many diffuse bounce rays from their hit points (cosine-distributed, fixed seed). Mrays/s is
  closest-hit throughput on {thread_text}: the median of the timed runs. All structures of a scene are built first and then timed taking turns (in order, each an
  untimed pass and a timed one, as often as the runs), so that a drift in the machine's speed
  during the process slows each alike, while each timed pass finds its structure in the
  caches, as one timed alone does (results collected before this timed one structure after
  the other: their `timing` field says which).
- Each round is a separate process on the same rays. Tables show the median over the rounds;
  a ratio of two structures is computed within each round and the median of those ratios is
  shown.
- SAH, node, BRef and work counts are exact and the same in every round. SAH is divided by the
  same scene box for every structure; Embree's structures report none.
- Structures: `embree-flat` and `embree-instanced` are Embree's BVHs over all triangles and
  over instances, with Embree's default scene flags and build quality (not
  `RTC_SCENE_FLAG_ROBUST`), as an Embree application gets them; `flat` is the project's BVH
  over all triangles; `twolevel` its BVH over instances (one BRef per instance); `rebraid` the
  partially re-braided top level with the project's default rules (SAH-tested opening, BRef
  boxes from transformed vertices); `paper`
  is the variant `{PAPER}`: the paper's rules (extent opening,
  transformed node boxes).
- Each structure is queried as its users query it: the project's through `Accel::intersect`,
  Embree's by `rtcIntersect1` on rays already in Embree's layout (converted and checked before
  the timing, `embree_glue/reference/embree_ray_batch.h`), so that no conversion counts
  against Embree. The instruction counts below query both the same way.
- A "{DASH}" marks a figure the structure or the command does not report.
"""


def section_commands(runs):
    out = ["## Commands\n",
           "Run from the repository root. `TMP` stands for a temporary folder.\n"]
    suites = []
    for run in runs:
        if run.suite not in suites:
            suites.append(run.suite)
    for suite in suites:
        members = [run for run in runs if run.suite == suite]
        setup, lines = [], []
        for run in members:
            setup += [code(a) for a in run.results[0].get("setup", []) if code(a) not in setup]
            if code(run.command) not in lines:
                lines.append(code(run.command))
        per_round = {}
        for run in members:
            for r in run.results:
                if r.get("seconds") is not None:
                    per_round[r.get("round", 0)] = per_round.get(r.get("round", 0), 0) + r["seconds"]
        collect = members[0].results[0].get("collect_command")
        intro = f"Suite `{suite}`"
        if collect:
            intro += f", `{code(collect)}`"
        if per_round:
            intro += f" (one round took about {median(per_round.values()) / 60:.1f} min)"
        if setup:
            out.append(intro + ", runs once:\n\n```sh\n" + "\n".join(setup) + "\n```\n")
            intro = "and then, in each round:"
        else:
            intro += ", runs in each round:"
        out.append(intro + "\n\n```sh\n" + "\n".join(lines) + "\n```\n")
    return "\n".join(out)


def rows_with(run, key):
    output = run.results[0]["output"]
    return isinstance(output, list) and output and isinstance(output[0], dict) and key in output[0]


def bench_runs(runs):
    return [run for run in runs if rows_with(run, "accel")]


def animate_runs(runs):
    return [run for run in runs if rows_with(run, "method")]


def stats_runs(runs, suite):
    """The runs of `suite` whose output is one `rebraid stats --json` object."""
    return [run for run in runs if run.suite == suite and isinstance(run.results[0]["output"], dict)
            and "structure_hash" in run.results[0]["output"]]


def instruction_runs(runs):
    return [run for run in runs if isinstance(run.results[0]["output"], dict)
            and "structures" in run.results[0]["output"]]


# Ratios of instructions per ray: each project structure to Embree's flat BVH, and the
# re-braided top level to Embree's instanced scene.
INSTRUCTION_RATIOS = [("flat", "embree-flat"), ("twolevel", "embree-flat"),
                      ("rebraid", "embree-flat"), ("rebraid", "embree-instanced")]


def section_instructions(runs):
    """Instructions per ray from bench/tools/count_instructions.py (exact: one round); ""
    when the results hold none (older result sets)."""
    if not runs:
        return ""
    outputs = [(run.name, run.results[0]["output"]) for run in runs]
    accels = []
    for _, output in outputs:
        accels += [row["accel"] for row in output["structures"] if row["accel"] not in accels]
    known = [a for a in DEFAULT_ACCELS if a in accels]
    accels = known + [a for a in accels if a not in known]
    ratios = [(a, b) for a, b in INSTRUCTION_RATIOS if a in accels and b in accels]
    rays = {kind: " or ".join(fmt_int(r) for r in sorted({o[f"rays_{kind}"] for _, o in outputs}))
            for kind in ("primary", "diffuse")}
    valgrind = sorted({output.get("valgrind") or "valgrind" for _, output in outputs})
    out = ["## Table 1c: instructions per ray\n",
           "Exact instruction counts, free of the timing noise of a shared machine\n"
           "(`bench/tools/count_instructions.py`): callgrind counts the instructions of a\n"
           "single-threaded loop (`build/bench/trace_rays`) that finds every ray's closest hit,\n"
           "then every ray's occlusion, so a figure is closest hit + occluded per ray, without the\n"
           "build.\n"
           "valgrind emulates no AVX-512, so Embree runs its AVX2 kernels and the project's\n"
           "structures theirs: both sides compare at AVX2. The rays are the bench's own, written\n"
           f"by `rebraid bench --save-rays`: {rays['primary']} primary and {rays['diffuse']}\n"
           f"diffuse rays per scene. Counted with {', '.join(valgrind)}. A ratio below 1: the\n"
           "first structure needs fewer instructions per ray.\n"]
    # The structures should agree on what the rays hit; say where they do not.
    found = ("hits_primary", "occluded_primary", "hits_diffuse", "occluded_diffuse")
    differing = [name for name, output in outputs
                 if len({tuple(row.get(f) for f in found) for row in output["structures"]}) > 1]
    out.append("Every structure found the same hits and occluded rays on every scene.\n"
               if not differing else
               "The structures' hit or occlusion counts differ on: " + ", ".join(differing) + ".\n")
    for kind in ("primary", "diffuse"):
        field = f"instructions_per_{kind}_ray"
        rows = []
        for name, output in outputs:
            by_accel = {row["accel"]: row for row in output["structures"]}

            def per_ray(accel):
                return by_accel[accel].get(field) if accel in by_accel else None

            def ratio(a, b):
                x, y = per_ray(a), per_ray(b)
                return x / y if x is not None and y else None

            rows.append([name] + [fmt_int(per_ray(a)) for a in accels]
                        + [fmt_ratio(ratio(a, b)) for a, b in ratios])
        out.append(f"### Instructions per {kind} ray (closest hit + occluded)\n")
        out.append(table(["scene"] + [label(a) for a in accels]
                         + [f"{label(a)} / {label(b)}" for a, b in ratios], rows))
    return "\n".join(out)


def section_structures(runs):
    """SAH and structure_hash per scene and structure, from `rebraid stats` (exact figures:
    a change that keeps behaviour keeps every one of them)."""
    by_scene, accels = {}, []
    for run in runs:
        output = run.results[0]["output"]
        scene, accel = run.name.rsplit("-", 1)[0], output["accel"]
        by_scene.setdefault(scene, {})[accel] = output
        accels += [accel] if accel not in accels else []
    header = ["scene"]
    for accel in accels:
        header += [f"{label(accel)} SAH", f"{label(accel)} structure_hash"]
    rows = []
    for scene, outputs in by_scene.items():
        row = [scene]
        for accel in accels:
            output = outputs.get(accel, {})
            row += [fmt(output.get("sah"), 4), f"`{output['structure_hash']:016x}`"
                    if output.get("structure_hash") is not None else "-"]
        rows.append(row)
    return ("## Structures: SAH and structure hash\n\n"
            "Exact and deterministic (the same on any thread count): a change meant to keep\n"
            "behaviour must leave every figure here as it is.\n\n" + table(header, rows))


def section_scenes(runs):
    rows = []
    for run in runs:
        accel = run.names("accel")[0]
        source = {"scenes": "built-in" if run.name == "default" else "shared",
                  "generated": "generated"}.get(run.suite, run.suite)
        hits_p, hits_d = run.first("accel", accel, "hits_primary"), run.first("accel", accel, "hits_diffuse")
        rays_p, rays_d = run.first("accel", accel, "rays_primary"), run.first("accel", accel, "rays_diffuse")
        rows.append([run.name, source, fmt_int(run.first("accel", accel, "triangles")),
                     fmt_int(run.first("accel", accel, "instances")),
                     fmt_int(run.first("accel", accel, "meshes")),
                     f"{fmt_int(rays_p)} ({fmt_int(hits_p)})", f"{fmt_int(rays_d)} ({fmt_int(hits_d)})"])
    return ("## Scenes\n\nTriangles over all instances; rays traced per run (rays that hit).\n\n"
            + table(["scene", "source", "triangles", "instances", "meshes", "primary rays (hit)",
                     "diffuse rays (hit)"], rows, left=2))


def per_scene_table(runs, accels, field, formatter):
    """Rows: scenes; columns: the structures that report `field` for some scene."""
    accels = [a for a in accels if any(run.value("accel", a, field) is not None for run in runs)]
    rows = [[run.name] + [formatter(run.value("accel", a, field)) for a in accels] for run in runs]
    return table(["scene"] + [label(a) for a in accels], rows)


RATIOS = [("flat", "embree-flat"), ("rebraid", "embree-flat"), ("rebraid", "embree-instanced"),
          ("rebraid", "twolevel"), (PAPER, "twolevel")]


def section_table1(runs, accels):
    out = ["## Table 1: SAH and ray throughput\n",
           "### SAH (lower is better)\n", per_scene_table(runs, accels, "sah", fmt),
           "### Primary rays, Mrays/s\n", per_scene_table(runs, accels, "mrays_primary", fmt),
           "### Diffuse rays, Mrays/s\n", per_scene_table(runs, accels, "mrays_diffuse", fmt)]
    for field, title in (("mrays_primary", "primary"), ("mrays_diffuse", "diffuse")):
        rows = [[run.name] + [fmt_ratio(run.ratio("accel", a, b, field)) for a, b in RATIOS]
                for run in runs]
        out.append(f"### Speed ratios, {title} rays (above 1: the first is faster)\n")
        out.append(table(["scene"] + [f"{label(a)} / {label(b)}" for a, b in RATIOS], rows))
    return "\n".join(out)


def section_table1b(runs, accels):
    project = [a for a in accels if a in PROJECT or a.startswith("rebraid:")]
    fields = ["nodes_per_diffuse_ray", "triangles_per_diffuse_ray", "object_entries_per_diffuse_ray"]
    if not any(run.value("accel", a, f) is not None for run in runs for a in project for f in fields):
        return ""
    out = ["## Table 1b: work per diffuse ray\n",
           "Counted in an untimed pass over the diffuse rays (exact). Object entries are top-level\n"
           "items a ray enters: one ray transform and one object-BVH traversal each. `work` is\n"
           "nodes + triangles, the two unit costs of the SAH, over `flat`'s.\n"]
    for field, title in (("nodes_per_diffuse_ray", "Nodes visited"),
                         ("triangles_per_diffuse_ray", "Triangles tested"),
                         ("object_entries_per_diffuse_ray", "Object entries")):
        out.append(f"### {title} per diffuse ray\n")
        out.append(per_scene_table(runs, project, field, fmt))
    rows = []
    for run in runs:
        def work(accel):
            n = run.value("accel", accel, "nodes_per_diffuse_ray")
            t = run.value("accel", accel, "triangles_per_diffuse_ray")
            return None if n is None or t is None else n + t
        base = work("flat")
        rows.append([run.name] + [fmt_ratio(work(a) / base if work(a) is not None and base else None)
                                  for a in project])
    out.append("### Work (nodes + triangles) over flat's\n")
    out.append(table(["scene"] + [label(a) for a in project], rows))
    return "\n".join(out)


def section_forests(runs, tracing_runs):
    """Table 2b: `rebraid stats` of twolevel and rebraid on the large generated forests, one
    process per structure and round: medians over the rounds; then Table 2c from
    `tracing_runs`, the suite's `rebraid bench` runs."""
    forests = {}
    for run in runs:
        forest, accel = run.name.rsplit("-", 1)
        values = {f: median([r["output"].get(f) for r in run.results])
                  for f in ("load_ms", "build_ms", "top_build_ms", "sah", "memory_bytes",
                            "peak_rss_bytes")}
        values["instances"] = run.results[0]["output"].get("instances")
        values["triangles"] = run.results[0]["output"].get("triangles")
        forests.setdefault(forest, {})[accel] = values
    header = ["forest", "instances", "instanced triangles", "load", "twolevel build",
              "rebraid build",
              "twolevel top", "rebraid top", "rebraid top / twolevel top", "twolevel SAH",
              "rebraid SAH", "twolevel memory (MiB)", "rebraid memory (MiB)",
              "twolevel peak RSS (MiB)", "rebraid peak RSS (MiB)"]
    rows = []
    for forest, by_accel in forests.items():
        two, re = by_accel.get("twolevel", {}), by_accel.get("rebraid", {})
        ratio = (re["top_build_ms"] / two["top_build_ms"]
                 if re.get("top_build_ms") is not None and two.get("top_build_ms") else None)
        rows.append([forest, fmt_int((two or re).get("instances")),
                     fmt_int((two or re).get("triangles")),
                     fmt_ms(median([two.get("load_ms"), re.get("load_ms")])),
                     fmt_ms(two.get("build_ms")), fmt_ms(re.get("build_ms")),
                     fmt_ms(two.get("top_build_ms")), fmt_ms(re.get("top_build_ms")),
                     fmt_ratio(ratio), fmt(two.get("sah")), fmt(re.get("sah")),
                     fmt_mib(two.get("memory_bytes")), fmt_mib(re.get("memory_bytes")),
                     fmt_mib(two.get("peak_rss_bytes")), fmt_mib(re.get("peak_rss_bytes"))])
    return ("## Table 2b: top levels at scale (ms)\n\n"
            "`rebraid stats` on `rebraid generate trees --instances N`, each structure in its own\n"
            "process (so the ratio is of the medians): loading the file (`load_ms`, the median\n"
            "over both structures' runs), full build (object BVHs and top level), the\n"
            "top level alone, SAH, the structure's memory and the process's peak resident memory\n"
            "(scene, structure and the SAH walk).\n\n" + table(header, rows)
            + section_forest_tracing(tracing_runs))


def section_forest_tracing(runs):
    """Table 2c: `rebraid bench` on the same forests: Mrays/s, and ratios taken per round."""
    if not runs:
        return ""
    kinds = (("primary", "mrays_primary"), ("diffuse", "mrays_diffuse"))
    header = ["forest"]
    for kind, _ in kinds:
        header += [f"embree-instanced {kind}", f"twolevel {kind}", f"rebraid {kind}",
                   f"rebraid / embree-instanced {kind}"]
    rows = []
    for run in runs:
        row = [run.name.rsplit("-", 1)[0]]
        for _, field in kinds:
            row += [fmt(run.value("accel", a, field)) for a in
                    ("embree-instanced", "twolevel", "rebraid")]
            row.append(fmt_ratio(run.ratio("accel", "rebraid", "embree-instanced", field)))
        rows.append(row)
    return ("\n### Table 2c: tracing at scale (Mrays/s)\n\n"
            "`rebraid bench` on the same forests, all three structures in one process on the same\n"
            "rays; the ratio is the median of each round's own.\n\n" + table(header, rows))


def section_table2(runs, accels):
    tops = [a for a in accels if a in ("twolevel", "rebraid") or a.startswith("rebraid:")]
    header = ["scene"] + [f"{label(a)} build" for a in accels]
    header += [f"{label(a)} top" for a in tops]
    header += [f"{label(a)} top / twolevel top" for a in tops if a != "twolevel"]
    rows = []
    for run in runs:
        row = [run.name] + [fmt_ms(run.value("accel", a, "build_ms")) for a in accels]
        row += [fmt_ms(run.value("accel", a, "top_build_ms")) for a in tops]
        row += [fmt_ratio(run.ratio("accel", a, "twolevel", "top_build_ms"))
                for a in tops if a != "twolevel"]
        rows.append(row)
    out = ["## Table 2: build times (ms)\n",
           "Full build of each structure (for the two-level ones: object BVHs and top level) and,\n"
           "for the two-level structures, the top level alone (its tree and the instances' records:\n"
           "what a frame that moves instances builds again).\n", table(header, rows)]
    rebraids = [a for a in tops if a != "twolevel"]
    if rebraids:
        header = ["scene", "instances"]
        for a in rebraids:
            header += [f"{label(a)} BRefs", f"{label(a)} budget", f"{label(a)} opened"]
        rows = []
        for run in runs:
            row = [run.name, fmt_int(run.first("accel", rebraids[0], "instances"))]
            for a in rebraids:
                row += [fmt_int(run.value("accel", a, k)) for k in ("brefs", "budget", "opened")]
            rows.append(row)
        out.append("### Re-braided top levels\n")
        out.append("BRefs in the top level, the budget of extra BRefs, and BRefs opened.\n")
        out.append(table(header, rows))
    return "\n".join(out)


def section_memory(runs, accels):
    if not any(run.value("accel", a, "memory_bytes") is not None for run in runs for a in accels):
        return ""
    rows = [[run.name] + [fmt_mib(run.value("accel", a, "memory_bytes")) for a in accels]
            for run in runs]
    return ("## Memory (MiB)\n\nBytes each structure holds, as it reports them (`memory_bytes`).\n\n"
            + table(["scene"] + [label(a) for a in accels], rows))


def tool_runs(runs, suite, key):
    """The runs of `suite` whose output is one JSON object holding `key`."""
    return [run for run in runs if run.suite == suite and isinstance(run.results[0]["output"], dict)
            and key in run.results[0]["output"]]


def section_preload(runs):
    """Embree's own viewer with and without the preload library (bench/tools/preload_viewer.py)."""
    if not runs:
        return ""

    def value(run, field):
        return median([r["output"].get(field) for r in run.results])

    def ratio(run, a, b):
        values = [r["output"][a] / r["output"][b] for r in run.results
                  if r["output"].get(a) is not None and r["output"].get(b)]
        return median(values)

    rows = []
    for run in runs:
        output = run.results[0]["output"]
        served = output.get("served")
        rows.append([run.name, fmt_int(output.get("instances")),
                     fmt(value(run, "embree_instanced_mrays")), fmt(value(run, "embree_flat_mrays")),
                     fmt(value(run, "preload_mrays")) if served else "not served",
                     fmt_ratio(ratio(run, "preload_mrays", "embree_instanced_mrays")),
                     fmt_ratio(ratio(run, "preload_mrays", "embree_flat_mrays")),
                     fmt(value(run, "rebraid_build_ms"), 1), fmt(value(run, "embree_objects_ms"), 1)])
    runs_per_round = sorted({len(r["output"]["runs"]["preload"]) for run in runs for r in run.results})
    return ("## Embree's viewer under the preload library\n\n"
            "Debian's `viewer` (embree-tools) renders each shared scene, exported with `rebraid\n"
            "export --embree-xml`, at 640x360 (`--benchmark 2 8`: its Mrays/s over 8 frames after 2):\n"
            "instanced (`--instancing geometry`) and flattened (`--instancing none`) by Embree, and\n"
            "instanced under `LD_PRELOAD=build/lib/librebraid_preload.so`. The three take turns\n"
            f"({' or '.join(str(n) for n in runs_per_round)} "
            f"run{'s' if runs_per_round[-1] > 1 else ''} each per round, their median); "
            "the table gives the median\nover rounds, and each ratio the median of the rounds' own. "
            "`rebraid build` is the preload's\nbuild of the instanced scene (its `REBRAID_PRELOAD_LOG` "
            "line), `Embree commit` the time the\nviewer takes to create and commit its Embree "
            "objects (its `--verbose 1` timeline), each\nfrom one small render.\n\n"
            + table(["scene", "instances", "Embree instanced", "Embree flat", "preload",
                     "preload / Embree instanced", "preload / Embree flat", "rebraid build (ms)",
                     "Embree commit (ms)"], rows))


def section_dropin(runs):
    """The drop-in example's benchmark (bench/tools/dropin_grid.py)."""
    if not runs:
        return ""
    out = ["## The drop-in example against Embree\n",
           "`examples/dropin` (an Embree renderer switched to `rebraid::EmbreeAccel`), built "
           "against the\ninstalled package, traces 640x480 camera rays through a grid of 24x24 "
           "instanced torus\nknots and through the same grid flattened, on one thread: "
           "`rtcIntersect1` on its own\nEmbree scene, `EmbreeAccel::intersect1` on the "
           "re-braided structure built from it, and\n`rtcIntersect1` on an Embree user-geometry "
           "scene that answers through EmbreeAccel. The modes\ntake turns; each figure is the "
           "median over rounds of the example's own median of 7, and\neach ratio the median of "
           "the rounds' own.\n"]
    for run in runs:
        rows = []
        first = run.results[0]["output"]
        for scene in sorted({r["scene"] for r in first["rows"]}):
            for mode in [r["mode"] for r in first["rows"] if r["scene"] == scene]:
                rounds = [row for r in run.results for row in r["output"]["rows"]
                          if row["scene"] == scene and row["mode"] == mode]
                ratios = [r["output"]["ratios"][scene][mode] for r in run.results
                          if mode in r["output"]["ratios"].get(scene, {})]
                build_ms = median([row["build_ms"] for row in rounds])
                rows.append([scene, f"`{mode}`", fmt(median([row["mrays_per_s"] for row in rounds])),
                             fmt_ratio(median(ratios)) if ratios else DASH,
                             fmt(build_ms, 1) if build_ms else DASH])
        out.append(table(["scene", "mode", "Mrays/s", "over rtcIntersect1", "build (ms)"], rows))
    return "\n".join(out)


def option(argv, name, default):
    return argv[argv.index(name) + 1] if name in argv[:-1] else default


def describe_animate(run):
    argv = run.command
    static = option(argv, "--static", None)
    dynamic = option(argv, "--dynamic", None)
    static_text = f"`{os.path.basename(static)}`" if static else "the default scene"
    dynamic_text = f"`{os.path.basename(dynamic)}`" if dynamic else "the built-in twisting object"
    copies = option(argv, "--copies", "4")
    frames = option(argv, "--frames", "30")
    width, height = option(argv, "--width", "640"), option(argv, "--height", "360")
    return (f"{copies} copies of {dynamic_text} in {static_text}; {frames} frames, each "
            f"{width}x{height} primary rays and one diffuse bounce")


def section_frames(runs):
    if not runs:
        return ""
    out = ["## Frames: animated objects in a static scene\n",
           "`rebraid animate`: per frame, pose the animated copies, update each method's structure\n"
           "and render. Per method (structure + object-BVH update strategy): the mean frame time\n"
           "and its parts, the worst frame, the SAH after the last frame and the initial build.\n"
           "Each figure is the median over the rounds of the run's value.\n"]
    fields = [("mean_frame_ms", "frame ms"), ("max_frame_ms", "worst frame ms"),
              ("mean_animation_ms", "animation ms"), ("mean_update_ms", "update ms"),
              ("mean_top_ms", "top ms"), ("mean_render_ms", "render ms")]
    for run in runs:
        out.append(f"### {run.name}\n")
        out.append(describe_animate(run) + ".\n")
        rows = []
        for method in run.names("method"):
            rows.append([method] + [fmt_ms(run.value("method", method, f)) for f, _ in fields]
                        + [fmt(run.value("method", method, "final_sah")),
                           fmt_ms(run.value("method", method, "build_ms"))])
        out.append(table(["method"] + [t for _, t in fields] + ["final SAH", "build ms"], rows))
    return "\n".join(out)


# ---------------------------------------------------------------- plots

def save_figure(plt, figure, axis, folder, name, caption):
    """Writes `figure` (with its legend) to folder/name, deterministically (no software tag),
    and returns the Markdown that shows it."""
    axis.legend(fontsize="small")
    figure.tight_layout()
    figure.savefig(os.path.join(folder, name), dpi=100, metadata={"Software": None})
    plt.close(figure)
    return f"![{caption}]({name})\n"


def draw_plots(out_file, scene_runs, frame_runs):
    """Figures beside `out_file`; returns their Markdown links ([] without matplotlib)."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("report.py: matplotlib is missing: no figures", file=sys.stderr)
        return {}
    stem = os.path.splitext(os.path.basename(out_file))[0]
    folder = os.path.dirname(os.path.abspath(out_file))
    os.makedirs(folder, exist_ok=True)
    links = {}
    if scene_runs:
        pairs = [("flat", "embree-flat"), ("twolevel", "embree-flat"), (PAPER, "embree-flat"),
                 ("rebraid", "embree-flat")]
        figure, axis = plt.subplots(figsize=(11, 4.5))
        width = 0.8 / len(pairs)
        for i, (a, b) in enumerate(pairs):
            values = [run.ratio("accel", a, b, "mrays_diffuse") or 0 for run in scene_runs]
            axis.bar([x + (i - (len(pairs) - 1) / 2) * width for x in range(len(scene_runs))],
                     values, width, label=label(a))
        axis.axhline(1.0, color="black", linewidth=0.8)
        axis.set_xticks(range(len(scene_runs)), [run.name for run in scene_runs], rotation=30,
                        ha="right")
        axis.set_ylabel("diffuse Mrays/s / embree-flat's")
        axis.set_title("Diffuse-ray throughput relative to Embree's flat BVH (median of rounds)")
        axis.grid(axis="y", alpha=0.3)
        links["scenes"] = save_figure(plt, figure, axis, folder, f"{stem}-diffuse.png",
                                      "Diffuse-ray throughput relative to embree-flat")
    for run in frame_runs:
        methods = run.names("method")
        parts = [("mean_animation_ms", "animation"), ("mean_update_ms", "update"),
                 ("mean_top_ms", "top"), ("mean_render_ms", "render")]
        figure, axis = plt.subplots(figsize=(10, 0.35 * len(methods) + 1.5))
        left = [0.0] * len(methods)
        for field, title in parts:
            values = [run.value("method", m, field) or 0 for m in methods]
            axis.barh(range(len(methods)), values, left=left, label=title)
            left = [l + v for l, v in zip(left, values)]
        axis.set_yticks(range(len(methods)), methods)
        axis.invert_yaxis()
        # Linear scale; bars far beyond the others are cut at the edge and labelled.
        typical = sorted(left)[len(left) // 2]
        limit = max([t for t in left if t <= 4 * typical] + [typical]) * 1.25
        if max(left) > limit:
            axis.set_xlim(0, limit)
            for y, total in enumerate(left):
                if total > limit:
                    axis.text(limit * 0.98, y, f"{total:.0f} ms", ha="right", va="center",
                              fontsize="small", color="white", fontweight="bold")
        axis.set_xlabel("mean frame ms (median of rounds)")
        axis.set_title(f"Frame time: {run.name}")
        axis.grid(axis="x", alpha=0.3)
        links[run.name] = save_figure(plt, figure, axis, folder,
                                      f"{stem}-frames-{run.name}.png", f"Frame time of {run.name}")
    return links


# ---------------------------------------------------------------- main

def report(results, generated_by, results_dir, plots_out=None):
    runs = group_runs(results)
    # The forests suite's bench runs go to Table 2c, not the per-scene tables.
    scene_runs = [run for run in bench_runs(runs) if run.suite != "forests"]
    forest_tracing = [run for run in bench_runs(runs) if run.suite == "forests"]
    frame_runs = animate_runs(runs)
    accels = ordered_accels(scene_runs)
    links = draw_plots(plots_out, scene_runs, frame_runs) if plots_out else {}
    structures = stats_runs(runs, "structures")
    forests = stats_runs(runs, "forests")
    instructions = section_instructions(instruction_runs(runs))
    preload = section_preload(tool_runs(runs, "preload", "preload_mrays"))
    dropin = section_dropin(tool_runs(runs, "dropin", "ratios"))
    parts = [
        "# Benchmark results\n",
        f"This file is generated by `{generated_by}` from the raw results in `{results_dir}/`\n"
        "(written by `bench/collect.py`). Do not edit it by hand: collect new results and\n"
        "regenerate it (see \"How to regenerate\" at the end).\n",
        section_setup(results, runs),
        section_method(runs),
        section_commands(runs),
    ]
    if structures:
        parts.append(section_structures(structures))
    if scene_runs:
        parts += [section_scenes(scene_runs), section_table1(scene_runs, accels)]
        if "scenes" in links:
            parts.append(links["scenes"])
        parts += [section_table1b(scene_runs, accels), instructions,
                  section_table2(scene_runs, accels), section_memory(scene_runs, accels)]
    if forests:
        parts.append(section_forests(forests, forest_tracing))
    else:
        parts.append(instructions)
    frames = section_frames(frame_runs)
    if frames and links:
        for run in frame_runs:
            if run.name in links:
                marker = f"### {run.name}\n"
                frames = frames.replace(marker, marker + "\n" + links[run.name], 1)
    parts.append(frames)
    parts.append(preload)
    parts.append(dropin)
    parts.append("## How to regenerate\n\n"
                 "From the repository root, after building `build/` (Release), on an otherwise idle\n"
                 "machine:\n\n"
                 "```sh\n"
                 "python3 bench/collect.py    # every suite, 5 rounds, into bench/results/\n"
                 "python3 bench/report.py     # bench/results/ -> bench/RESULTS.md\n"
                 "```\n\n"
                 "`python3 bench/collect.py --help` lists the suites and options; `--quick --out DIR`\n"
                 "checks the pipeline in about three minutes without touching bench/results/.\n"
                 "`python3 bench/report.py --plots` also draws the figures (needs matplotlib).\n")
    return "\n".join(p.rstrip("\n") + "\n" for p in parts if p)


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--results", default=RESULTS_DIR,
                        help=f"folder of result files (default {RESULTS_DIR}/)")
    parser.add_argument("--out", default="bench/RESULTS.md", help="report to write")
    parser.add_argument("--plots", action="store_true",
                        help="also write figures (PNG) beside the report (needs matplotlib)")
    args = parser.parse_args()
    results = load_results(repo_path(args.results))
    if not results:
        sys.exit(f"report.py: no result files under {args.results}")
    generated_by = "python3 bench/report.py"
    if args.results != RESULTS_DIR:
        generated_by += f" --results {args.results}"
    if args.out != "bench/RESULTS.md":
        generated_by += f" --out {args.out}"
    if args.plots:
        generated_by += " --plots"
    out_file = repo_path(args.out)
    os.makedirs(os.path.dirname(out_file), exist_ok=True)
    text = report(results, generated_by, args.results.rstrip("/"), out_file if args.plots else None)
    with open(out_file, "w", newline="\n") as f:
        f.write(text)
    print(f"report.py: wrote {args.out} from {len(results)} result files", file=sys.stderr)


if __name__ == "__main__":
    main()
