#!/usr/bin/env python3
"""Cost of cohesive elements (not a test): the same scenes meshed without and with `--cohesive`.

    python3 validation/bench/cohesive_cost.py BUILD/bin/cisamr [--reps 5] [--out DIR] [--only CASE,...]
                                              [--formats vtu,msh,inp] [--wait-idle S]

Cases (each a pair A = plain, B = --cohesive; runs interleaved A B A B ..., every format in
turn within a repetition, so each case has reps x formats pairs):
  spheres300   3D: data/bench/spheres300.json (300 spheres in the unit cube, h 0.02, one
               level), the 3D benchmark named by issue #13 ("meshing time and memory with
               and without --cohesive").
  circles2000  2D: 2,000 circles of two phases (~30 % area) in a matrix, the circles2000
               packing of periodic_cost.py with periodic false (`cisamr pack`), h 1, one level.

Per run: `cisamr mesh --report` phase times, the command's wall time, CPU time (user + system)
and peak RSS (/usr/bin/time), the output's size. "mesh s" is the report's total minus read
and write (the meshing itself: oracle, stages, cohesive insertion, quality pass); elements/s
and bytes/element divide by the bulk element count (triangles or tetrahedra; cohesive cells
are counted apart). Times are medians over the runs, and min; a B/A ratio is the median of
the pairs' own ratios (the two runs of a pair are back to back, so a disturbance hits both
or few). The insertion's own time is the report's phase "cohesive" when the report lists
it; otherwise (it is timed but not listed) the median over pairs of the growth of the
unlisted remainder, total - read - write - listed phases, from A to B. Cohesive cells: the
.vtu's NumberOfCells minus the report's elements, checked against the .inp's COH2D4/COH3D6
lines (or the report's cohesive count where it has one); extra nodes: B's nodes minus A's.
The bulk mesh must be the same: equal checksums where the report's checksum covers the bulk
only, else equal per-phase element counts and measures. Writes DIR/cohesive_cost.md (the
tables) and DIR/cohesive_cost.json.
Run it on an idle machine: timings taken while something else compiles are worthless
(--wait-idle S holds each pair until nothing else runs, for S seconds at most).
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import time

PHASES = ["oracle", "samr", "radapt", "faceswap", "subdivide", "assemble", "cohesive", "quality"]
NOT_MESHING = ["read", "write", "total"]


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode not in (0, 3):  # 3: written, above the bound (reported, not fatal here)
        sys.exit(f"cohesive_cost: {' '.join(cmd)} failed ({r.returncode}):\n{r.stderr}")
    return r


def busy_fraction(seconds=1.0):
    """Share of all CPUs not idle over `seconds` (/proc/stat), this script's own children included."""
    def sample():
        f = [int(x) for x in open("/proc/stat").readline().split()[1:]]
        return f[3] + f[4], sum(f)  # idle + iowait, total
    i0, t0 = sample()
    time.sleep(seconds)
    i1, t1 = sample()
    return 1 - (i1 - i0) / max(1, t1 - t0)


def wait_idle(limit_s, threshold=0.1):
    """Waits (at most limit_s) until the machine is idle; returns whether it was."""
    deadline = time.time() + limit_s
    while True:
        if busy_fraction() < threshold:
            return True
        if time.time() > deadline:
            return False
        time.sleep(4)


def vtu_cells(path):
    with open(path, "rb") as f:
        head = f.read(1 << 16).decode("ascii", "replace")
    return int(re.search(r'NumberOfCells="(\d+)"', head).group(1))


def inp_cohesive(path):
    """COH2D4/COH3D6 element lines of an .inp, per ELSET."""
    sets, current = {}, None
    with open(path) as f:
        for line in f:
            if line.startswith("*"):
                current = None
                if line.upper().startswith("*ELEMENT,") and "TYPE=COH" in line.upper().replace(" ", ""):
                    current = re.search(r"ELSET=([^,\s]+)", line, re.I).group(1)
                    sets.setdefault(current, 0)
            elif current is not None and line.strip():
                sets[current] += 1
    return sets


def mesh_once(cisamr, scene, out, tag, fmt, cohesive):
    report = os.path.join(out, tag + ".report.json")
    target = os.path.join(out, tag + "." + fmt)
    cmd = [cisamr, "mesh", scene, "-o", target, "--report", report, "-q"] + (["--cohesive"] if cohesive else [])
    r = run(["/usr/bin/time", "-f", "TIME %e %M %U %S"] + cmd)
    line = [l for l in r.stderr.splitlines() if l.startswith("TIME ")][-1].split()
    j = json.load(open(report))
    t = {k: v["max"] for k, v in j["timings_s"].items()}
    listed = sum(v for k, v in t.items() if k not in NOT_MESHING)
    rec = {
        "format": fmt,
        "elements": j["elements"],
        "nodes": j["nodes"],
        "wall_s": float(line[1]),
        "rss_mib": int(line[2]) / 1024,
        "cpu_s": float(line[3]) + float(line[4]),  # user + system: less sensitive to other load than wall
        "total_s": j["total_s"],
        "mesh_s": j["total_s"] - t.get("read", 0) - t.get("write", 0),
        "write_s": t.get("write", 0),
        "unlisted_s": j["total_s"] - t.get("read", 0) - t.get("write", 0) - listed,
        "phases": {p: t[p] for p in PHASES if p in t},
        "checksum": j["checksum"],
        "phase_figures": [(p["id"], p["elements"], p["measure"]) for p in j["phases"]],
        "report_cohesive": j.get("cohesive", {}).get("elements"),  # newer reports count them
        "bytes": os.path.getsize(target),
    }
    if fmt == "vtu":
        rec["cells"] = vtu_cells(target)
    if fmt == "inp" and cohesive:
        rec["inp_cohesive"] = inp_cohesive(target)
    os.remove(target)
    return rec


def med(values):
    return statistics.median(list(values))


def side_summary(recs, formats):
    s = {
        "elements": recs[0]["elements"],
        "nodes": recs[0]["nodes"],
        "mesh_s": med(r["mesh_s"] for r in recs),
        "mesh_s_min": min(r["mesh_s"] for r in recs),
        "total_s": med(r["total_s"] for r in recs),
        "cpu_s": med(r["cpu_s"] for r in recs),
        "phases": {p: med(r["phases"].get(p, 0) for r in recs) for p in PHASES},
        "reported": sorted({p for r in recs for p in r["phases"]}),
        "checksums": sorted({r["checksum"] for r in recs}),
        "phase_figures": sorted({tuple(r["phase_figures"]) for r in recs}),
        "report_cohesive": sorted({r["report_cohesive"] for r in recs if r["report_cohesive"] is not None}),
        "rss_mib": med(r["rss_mib"] for r in recs),
        "runs_mesh_s": [round(r["mesh_s"], 4) for r in recs],
        "formats": {},
    }
    for fmt in formats:
        fr = [r for r in recs if r["format"] == fmt]
        s["formats"][fmt] = {k: med(r[k] for r in fr) for k in ("bytes", "write_s", "wall_s", "rss_mib")}
    s["vtu_cells"] = sorted({r["cells"] for r in recs if "cells" in r})
    inp = [r["inp_cohesive"] for r in recs if "inp_cohesive" in r]
    s["inp_cohesive"] = inp[0] if inp else None
    return s


def paired(A, B, formats):
    ratio = lambda key, pairs: med(b[key] / a[key] for a, b in pairs)
    pairs = list(zip(A, B))
    s = {k: ratio(k, pairs) for k in ("mesh_s", "total_s", "cpu_s", "rss_mib")}
    s["cohesive_s"] = med(b["phases"]["cohesive"] for b in B) if all("cohesive" in b["phases"] for b in B) \
        else med(b["unlisted_s"] - a["unlisted_s"] for a, b in pairs)
    s["cohesive_from"] = "report" if all("cohesive" in b["phases"] for b in B) else "derived"
    s["wall_s"] = {fmt: ratio("wall_s", [(a, b) for a, b in pairs if a["format"] == fmt]) for fmt in formats}
    return s


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("cisamr")
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--out", default="/tmp/cisamr_cohesive_cost")
    ap.add_argument("--only", help="comma-separated case names")
    ap.add_argument("--formats", default="vtu,msh,inp", help="comma-separated output formats (vtu first)")
    ap.add_argument("--wait-idle", type=float, default=0, metavar="S",
                    help="before each A/B pair wait up to S seconds for the machine to be idle "
                         "(under 10 %% of its CPUs busy over 1 s); pairs started busy are counted")
    a = ap.parse_args()
    cisamr = os.path.abspath(a.cisamr)
    repo = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    os.makedirs(a.out, exist_ok=True)
    o = lambda name: os.path.join(a.out, name)
    formats = a.formats.split(",")

    circles_spec = {  # periodic_cost.py's circles2000, not periodic
        "format": "cisamr-pack/1", "dimension": 2, "seed": 7,
        "domain": {"min": [0, 0], "max": [400, 400], "periodic": False},
        "mesh": {"h": 1.0, "levels": 1},
        "phases": [{"id": 1, "name": "matrix"}, {"id": 2, "name": "particle"}, {"id": 3, "name": "fibre"}],
        "matrix_phase": 1,
        "populations": [
            {"name": "a", "shape": "circle", "phase": 2, "count": 1000,
             "size": {"law": "uniform", "min": 2.0, "max": 3.6}, "min_gap": 0.5},
            {"name": "b", "shape": "circle", "phase": 3, "count": 1000,
             "size": {"law": "uniform", "min": 2.0, "max": 3.6}, "min_gap": 0.5}]}

    def packed(spec, name):
        spec_path = o(name + ".pack.json")
        json.dump(spec, open(spec_path, "w"), indent=1)
        run([cisamr, "pack", spec_path, "-o", o(name), "-q"])
        return o(name)

    cases = {
        "spheres300": lambda: os.path.join(repo, "data/bench/spheres300.json"),
        "circles2000": lambda: packed(circles_spec, "c2000.json"),
    }
    if a.only:
        cases = {k: v for k, v in cases.items() if k in a.only.split(",")}

    results = {}
    busy_pairs = 0
    for name, make in cases.items():
        scene = make()
        recs = {"A": [], "B": []}
        for rep in range(a.reps):
            for fmt in formats:
                if a.wait_idle > 0 and not wait_idle(a.wait_idle):
                    busy_pairs += 1
                for side in "AB":
                    recs[side].append(mesh_once(cisamr, scene, a.out, f"run-{side}", fmt, side == "B"))
        results[name] = {side: side_summary(r, formats) for side, r in recs.items()}
        results[name]["B/A"] = paired(recs["A"], recs["B"], formats)
        print(f"{name}: done", file=sys.stderr)

    bold = lambda x: f"**{x:.3f}**"
    shown = [p for p in PHASES if p not in ("oracle", "cohesive")]  # the oracle is not timed apart sequentially
    t1 = ["| case | mode | bulk elements | mesh s, median (min) | B / A | M elements / s | "
          + " | ".join(shown) + " | cohesive | report total s | B / A | CPU s | B / A |",
          "|---|---|---:|---:|---:|---:|" + "---:|" * len(shown) + "---:|---:|---:|---:|---:|"]
    t2 = ["| case | mode | nodes | cohesive cells | peak RSS MiB | B / A | bytes / element | "
          + " | ".join(f".{f} MiB" for f in formats) + " |",
          "|---|---|---:|---:|---:|---:|---:|" + "---:|" * len(formats)]
    extra = []
    for name, r in results.items():
        A, B, q = r["A"], r["B"], r["B/A"]
        from_vtu = [c - B["elements"] for c in B["vtu_cells"]]
        coh_cells = (B["report_cohesive"] or from_vtu or [0])[0]
        extra_nodes = f" (+{B['nodes'] - A['nodes']:,})"
        for side, x in (("A", A), ("B", B)):
            one = side == "A"
            phases = " | ".join("–" if p not in x["reported"] else f"{x['phases'][p]:.3f}" for p in shown)
            coh = "–" if one else f"{q['cohesive_s']:.3f}" + (" *" if q["cohesive_from"] == "derived" else "")
            t1.append(f"| {name} | {'plain' if one else '--cohesive'} | {x['elements']:,} | "
                      f"{x['mesh_s']:.3f} ({x['mesh_s_min']:.3f}) | {'1' if one else bold(q['mesh_s'])} | "
                      f"{x['elements'] / x['mesh_s'] / 1e6:.3f} | {phases} | {coh} | {x['total_s']:.3f} | "
                      f"{'1' if one else bold(q['total_s'])} | {x['cpu_s']:.2f} | {'1' if one else bold(q['cpu_s'])} |")
            sizes = " | ".join(f"{x['formats'][f]['bytes'] / 2**20:.1f}" + ("" if one else
                               f" ({x['formats'][f]['bytes'] / A['formats'][f]['bytes']:.3f})") for f in formats)
            t2.append(f"| {name} | {'plain' if one else '--cohesive'} | {x['nodes']:,}"
                      f"{'' if one else extra_nodes} | {0 if one else coh_cells:,} | "
                      f"{x['rss_mib']:.0f} | {'1' if one else bold(q['rss_mib'])} | "
                      f"{x['rss_mib'] * 2**20 / x['elements']:.0f} | {sizes} |")
        inp = B["inp_cohesive"]
        inp_total = sum(inp.values()) if inp else None
        if len(set(B["report_cohesive"] + from_vtu)) > 1:
            extra.append(f"- {name}: WARNING: cohesive counts differ: report {B['report_cohesive']}, .vtu {from_vtu}")
        extra.append(
            f"- {name}: {coh_cells:,} cohesive cells, {B['nodes'] - A['nodes']:,} extra nodes "
            f"(+{100 * (B['nodes'] - A['nodes']) / A['nodes']:.1f} %); insertion {q['cohesive_s']:.3f} s "
            f"({q['cohesive_from']}), {q['cohesive_s'] / max(coh_cells, 1) * 1e6:.2f} µs per cohesive cell, "
            f"{100 * q['cohesive_s'] / A['mesh_s']:.1f} % of the plain meshing; .inp element sets {inp}"
            + ("" if inp_total in (None, coh_cells) else f" WARNING: the .inp holds {inp_total} cohesive cells"))
        # Older reports' checksum covers the bulk cells only; newer ones count the cohesive cells
        # too, and then the bulk is compared by its per-phase element counts and measures.
        if len(A["checksums"]) > 1 or len(B["checksums"]) > 1:
            extra.append(f"- {name}: WARNING: repeated runs gave different meshes")
        if B["report_cohesive"]:
            same = A["phase_figures"] == B["phase_figures"] and A["elements"] == B["elements"]
            how = "per-phase element counts and measures"
        else:
            same = A["checksums"] == B["checksums"]
            how = f"checksum {A['checksums'][0]}"
        extra.append(f"- {name}: " + (f"the same bulk mesh with and without --cohesive ({how})" if same
                                      else f"WARNING: the bulk mesh differs with --cohesive ({how})"))
    if any(r["B/A"]["cohesive_from"] == "derived" for r in results.values()):
        extra.append("- *: the report does not list the phase; derived per pair as the growth of the unlisted "
                     "remainder (total − read − write − listed phases)")
    if a.wait_idle > 0:
        extra.append(f"- {busy_pairs} of {a.reps * len(formats) * len(results)} pairs started while the machine was "
                     f"busy (after waiting {a.wait_idle:g} s)")

    t3 = ["| case | format | write s plain | write s --cohesive | wall s plain | wall s --cohesive | B / A "
          "| peak RSS MiB plain | --cohesive |",
          "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for name, r in results.items():
        for fmt in formats:
            fa, fb = r["A"]["formats"][fmt], r["B"]["formats"][fmt]
            t3.append(f"| {name} | .{fmt} | {fa['write_s']:.3f} | {fb['write_s']:.3f} | {fa['wall_s']:.2f} | "
                      f"{fb['wall_s']:.2f} | {r['B/A']['wall_s'][fmt]:.3f} | {fa['rss_mib']:.0f} | {fb['rss_mib']:.0f} |")
    text = "\n".join(t1 + [""] + t2 + [""] + extra + [""] + t3) + "\n"
    print(text)
    open(o("cohesive_cost.md"), "w").write(text)
    json.dump(results, open(o("cohesive_cost.json"), "w"), indent=1)


if __name__ == "__main__":
    main()
