#!/usr/bin/env python3
"""Tables of bench_parallel.sh: bench_table.py TAG REPS (in the output folder).

Reads TAG-seq.R.json, TAG-r1-nN.R.json and TAG-r2-nN.R.json (R = 1..REPS, `cisamr mesh
--report`), keeps per configuration the run with the median total time, and prints two
Markdown tables: totals (with the checksum of every run compared with the sequential one,
the partitions' load, cost and kernel-time spreads) and phase times (min / max / mean over
ranks)."""
import glob
import json
import re
import statistics
import sys

tag, reps = sys.argv[1], int(sys.argv[2])
try:  # runs that started while another process was busy (bench_parallel.sh, wait_idle)
    busy = set(open("busy.txt").read().split())
except FileNotFoundError:
    busy = set()


def runs(name):
    out = []
    for r in range(1, reps + 1):
        try:
            j = json.load(open(f"{name}.{r}.json"))
        except FileNotFoundError:
            continue
        try:
            j["_rss_mb"] = int(open(f"{name}.{r}.rss").read().split()[-1]) / 1024
        except (FileNotFoundError, ValueError, IndexError):
            j["_rss_mb"] = None
        out.append(j)
    return out


def median_run(js):
    js = sorted(js, key=lambda j: j["total_s"])
    return js[(len(js) - 1) // 2]


names = [f"{tag}-seq"]
key = lambda n: (int(re.search(r"-r(\d+)-", n).group(1)), int(re.search(r"-n(\d+)$", n).group(1)))
names += sorted({re.sub(r"\.\d+\.json$", "", f) for f in glob.glob(f"{tag}-r*-n*.json")}, key=key)
seq_runs = runs(names[0])
seq = median_run(seq_runs)
ref = seq["checksum"]
dim = seq["dimension"]
cells_key = "coarse_cells" if dim == 2 else "coarse_cubes"
domain = seq["algorithm"][cells_key]
t_seq = seq["total_s"]
t_r1n1 = None

print(f"Scene: {seq['scene']} ({dim}D), {seq['elements']:,} elements, checksum {ref}; "
      f"median of {reps} runs per row.\n")
print("| run | ranks | N | total s (median; min-max) | speed-up vs sequential | efficiency | "
      "coarse cells meshed / domain | kernel µs per meshed cell | load max/mean | cost max/mean | "
      "kernel max/mean | peak RSS MB | checksums = sequential |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
phase_rows = []
for name in names:
    js = runs(name)
    if not js:
        continue
    j = median_run(js)
    ts = [x["total_s"] for x in js]
    same = all(x["checksum"] == ref for x in js)
    ranks = j.get("ranks", 1)
    if name.endswith("-seq"):
        n, meshed, per_cell, imb, cost_imb, kernel_imb = "-", 1.0, None, None, None, None
    else:
        parts = j["partitions"]
        n = len(parts)
        meshed = 1 + sum(p["ghost_coarse_cells"] for p in parts) / domain
        box = lambda p: __import__("math").prod(b - a for a, b in zip(p["lattice_min"], p["lattice_max"]))
        cells = sum(box(p) + p["ghost_coarse_cells"] for p in parts)
        per_cell = 1e6 * sum(p["kernel_s"] for p in parts) / cells
        imb = j["load"]["imbalance"]
        # What the partitioner balanced (3D: the load and the ghost's; absent before
        # 92590af) and what the partitions' kernels took: the slowest over the mean.
        cost_imb = j["load"].get("cost_imbalance")
        kernel = [p["kernel_s"] for p in parts]
        kernel_imb = max(kernel) / statistics.mean(kernel) if statistics.mean(kernel) > 0 else None
        if ranks == 1 and n == 1:
            t_r1n1 = j["total_s"]
    speedup = t_seq / j["total_s"]
    eff = f"{speedup / ranks:.2f}" if ranks > 1 else "-"
    rss = max((x["_rss_mb"] for x in js if x["_rss_mb"]), default=None)
    label = name[len(tag) + 1:] + (" (busy)" if any(f"{name}.{r}" in busy for r in range(1, reps + 1)) else "")
    print(f"| {label} | {ranks} | {n} | {j['total_s']:.2f} ({min(ts):.2f}-{max(ts):.2f}) | {speedup:.2f} | {eff} | "
          f"{meshed:.2f} | {'-' if per_cell is None else f'{per_cell:.1f}'} | {'-' if imb is None else f'{imb:.2f}'} | "
          f"{'-' if cost_imb is None else f'{cost_imb:.2f}'} | {'-' if kernel_imb is None else f'{kernel_imb:.2f}'} | "
          f"{'-' if rss is None else f'{rss:.0f}'} | {'yes' if same else 'NO'} ({len(js)}) |")
    phase_rows.append((label, j))

phases = ["read", "partition", "ghost", "oracle", "samr", "radapt"] + (["faceswap"] if dim == 3 else []) + \
         ["subdivide", "assemble", "merge", "quality", "write"]
print("\nPhase times of the median run, seconds: max over ranks (min / mean when they differ).\n")
print("| run | " + " | ".join(phases) + " |")
print("|---|" + "---|" * len(phases))
for label, j in phase_rows:
    t = j["timings_s"]
    cells = []
    for p in phases:
        if p not in t:
            cells.append("-")
            continue
        lo, hi, mean = t[p]["min"], t[p]["max"], t[p]["mean"]
        cells.append(f"{hi:.2f}" if hi - lo < 0.005 else f"{hi:.2f} ({lo:.2f} / {mean:.2f})")
    print(f"| {label} | " + " | ".join(cells) + " |")
