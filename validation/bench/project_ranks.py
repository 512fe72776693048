#!/usr/bin/env python3
"""What N ranks, one partition each, would take, from runs on one process.

    cisamr mesh SCENE -o s.vtu --report seq.1.json                      # sequential
    cisamr mesh SCENE -o p.pvtu --partitions N --report parts.1.json    # N partitions, one rank
    ...                                                                 # a few times each
    validation/bench/project_ranks.py --sequential seq.*.json --partitions parts.*.json

The one-rank run meshes the N partitions one after another, each alone on the core, and its
report times each partition's kernel (`kernel_s`, and with exchanges near faces its four
parts between them, `kernel_stages_s`). With a rank per partition every rank waits at each
exchange for the slowest partition, so the kernel takes the sum over parts of their maxima;
the phases after it (assembling, merging, quality statistics, writing) take the largest
partition's share of the one-rank run's; the scene is read and the ghost regions found on
every rank, the partitioning on rank 0 while the others wait. What this does not see: the
messages' latency and bandwidth, and what a machine loses with N processes busy at once
(memory bandwidth, a shared cache, turbo clocks): compare with a measured run where one can
be had (SCALING.md: at 876a47f the projection and a 16-core machine's run, side by side).

Shared machines are noisy, and the largest of N noisy times is biased upwards: give several
runs of each; every phase, every partition's kernel time and every part of it is their
median. (Let each run's output reach the disk before the next starts, `sync`: E4's 1 GB
written back during the next run slowed its partitions by up to 60 %.)
"""
import argparse
import json
import sys

# Phases whose work is a partition's, done by the rank holding it: on N ranks the largest
# partition's share (by elements) of what the one-rank run spent on all of them.
PER_PARTITION = ("oracle", "exchange", "cohesive", "assemble", "merge", "quality", "write", "periodic")
# Phases every rank does whole (reading, the ghost regions' index) or rank 0 does while the
# others wait (partitioning).
WHOLE = ("read", "ghost", "partition")
# The kernel's phases, timed per partition in `partitions[]` instead.
KERNEL = ("samr", "radapt", "faceswap", "subdivide", "cutcells", "kernel")


def median(values):
    v = sorted(values)
    return v[len(v) // 2] if len(v) % 2 else (v[len(v) // 2 - 1] + v[len(v) // 2]) / 2


def refuse(path, field, what):
    """Bad input: one line naming the file, the field and what is wrong; exit code 2."""
    print("project_ranks.py: %s: %s: %s" % (path, field, what), file=sys.stderr)
    sys.exit(2)


def read_report(path, partitioned):
    """A cisamr-report/1 file with what the projection reads; `partitioned`: of a run with
    --partitions on one rank (each partition's kernel time), else of the sequential mesher."""
    try:
        with open(path) as f:
            r = json.load(f)
    except (OSError, ValueError) as e:
        refuse(path, "-", "not a readable JSON report (%s)" % e)
    if not isinstance(r, dict) or r.get("format") != "cisamr-report/1":
        refuse(path, "format", "not a cisamr-report/1 (cisamr mesh --report)")
    for field in ("checksum", "total_s", "timings_s", "partitions"):
        if field not in r:
            refuse(path, field, "missing (a report of cisamr mesh with its checksum)")
    if partitioned:
        if r.get("ranks") != 1 or not r["partitions"] or "kernel_s" not in r["partitions"][0]:
            refuse(path, "partitions", "the partitions' run must be cisamr mesh --partitions N on one rank")
    elif r["partitions"] and "kernel_s" in r["partitions"][0]:
        refuse(path, "partitions", "a partitioned run given as the sequential one")
    return r


def median_report(paths, runs, what):
    """One report whose times are the runs' medians (phases, total, each partition's kernel
    and its parts); the runs must be of one mesh."""
    first = runs[0]
    for path, r in zip(paths, runs):
        if r["checksum"] != first["checksum"] or len(r["partitions"]) != len(first["partitions"]):
            refuse(path, "checksum", "the %s runs are not of one mesh (%s against %s's %s)"
                   % (what, r["checksum"], paths[0], first["checksum"]))
    out = json.loads(json.dumps(first))
    out["total_s"] = median([r["total_s"] for r in runs])
    names = set().union(*(r["timings_s"] for r in runs))
    out["timings_s"] = {n: {"max": median([r["timings_s"].get(n, {"max": 0.0})["max"] for r in runs])} for n in names}
    for i, p in enumerate(out["partitions"]):
        if "kernel_s" in p:
            p["kernel_s"] = median([r["partitions"][i]["kernel_s"] for r in runs])
        if "kernel_stages_s" in p:
            p["kernel_stages_s"] = [median([r["partitions"][i]["kernel_stages_s"][s] for r in runs])
                                    for s in range(len(p["kernel_stages_s"]))]
    return out


def phase_seconds(report):
    return {name: t["max"] for name, t in report["timings_s"].items() if name != "total"}


def project(sequential, parts):
    partitions = parts["partitions"]
    n = len(partitions)
    phases = phase_seconds(parts)
    elements = [p["elements"] for p in partitions]
    largest_share = max(elements) / sum(elements)

    staged = all("kernel_stages_s" in p for p in partitions)
    if staged:
        stages = len(partitions[0]["kernel_stages_s"])
        stage_max = [max(p["kernel_stages_s"][s] for p in partitions) for s in range(stages)]
        kernel = sum(stage_max)
    else:
        stage_max = [max(p["kernel_s"] for p in partitions)]
        kernel = stage_max[0]
    kernel_sum = sum(p["kernel_s"] for p in partitions)
    box_cells = 0  # the boxes tile the domain
    for p in partitions:
        cells = 1
        for lo, hi in zip(p["lattice_min"], p["lattice_max"]):
            cells *= hi - lo
        box_cells += cells
    kernel_max = max(p["kernel_s"] for p in partitions)

    terms = {}
    for name in WHOLE:
        terms[name] = phases.get(name, 0.0)
    terms["kernel"] = kernel
    for name in PER_PARTITION:
        if name in phases:
            terms[name] = phases[name] * largest_share
    unknown = [name for name in phases if name not in WHOLE + PER_PARTITION + KERNEL]
    for name in unknown:  # a phase this script does not know: counted whole, and said
        terms[name] = phases[name]
    # Time outside every phase (setting up, freeing the mesh): the partitions' share.
    outside = max(0.0, parts["total_s"] - sum(phases.values()))
    terms["outside phases"] = outside * largest_share
    projected = sum(terms.values())

    one = sequential["total_s"]
    seq_phases = phase_seconds(sequential)
    seq_kernel = sum(seq_phases.get(name, 0.0) for name in KERNEL)
    return {
        "partitions": n,
        "sequential_s": one,
        "sequential_kernel_s": seq_kernel,
        "projected_s": projected,
        "efficiency": one / (n * projected),
        "terms": terms,
        "unknown_phases": unknown,
        "kernel": {
            "slowest_s": kernel_max,
            "sum_over_partitions_s": kernel_sum,
            "ghost_factor": kernel_sum / seq_kernel if seq_kernel > 0 else None,
            "slowest_over_mean": kernel_max * n / kernel_sum,
            "stages_max_s": stage_max,
            "waits_over_slowest": kernel / kernel_max,
        },
        "cells_meshed_over_domain": (box_cells + sum(p["ghost_coarse_cells"] for p in partitions)) / box_cells,
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sequential", nargs="+", required=True, help="reports of sequential runs (cisamr mesh --report)")
    parser.add_argument("--partitions", nargs="+", required=True, help="reports of N-partition runs on one rank")
    parser.add_argument("--json", action="store_true", help="print the projection as JSON")
    args = parser.parse_args()
    reports = []
    for paths, what in ((args.sequential, "sequential"), (args.partitions, "partitions'")):
        runs = [read_report(path, what != "sequential") for path in paths]
        reports.append(median_report(paths, runs, what))
    if reports[0]["checksum"] != reports[1]["checksum"]:
        refuse(args.partitions[0], "checksum", "not the sequential runs' mesh (%s against %s)"
               % (reports[1]["checksum"], reports[0]["checksum"]))
    p = project(*reports)
    if args.json:
        print(json.dumps(p, indent=1))
        return
    n, k = p["partitions"], p["kernel"]
    print("sequential %.2f s; %d ranks projected %.2f s (ideal %.2f s): efficiency %.3f"
          % (p["sequential_s"], n, p["projected_s"], p["sequential_s"] / n, p["efficiency"]))
    print("kernel: all partitions %.2f s = %.3f x the sequential kernel's %.2f s (the ghost); "
          "slowest %.3f s = %.3f x the mean; with the waits at exchanges %.3f s (x %.3f)"
          % (k["sum_over_partitions_s"], k["ghost_factor"] or 0, p["sequential_kernel_s"], k["slowest_s"],
             k["slowest_over_mean"], p["terms"]["kernel"], k["waits_over_slowest"]))
    print("cells meshed over the domain's: %.3f" % p["cells_meshed_over_domain"])
    for name, seconds in sorted(p["terms"].items(), key=lambda kv: -kv[1]):
        print("  %-15s %7.3f s" % (name, seconds))
    if p["unknown_phases"]:
        print("phases counted whole (unknown here): " + ", ".join(p["unknown_phases"]))


if __name__ == "__main__":
    main()
