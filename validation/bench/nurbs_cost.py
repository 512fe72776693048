#!/usr/bin/env python3
"""Cost of NURBS surfaces (not a test): the same spheres meshed as analytic spheres and as exact NURBS.

    python3 validation/bench/nurbs_cost.py BUILD/bin/cisamr [--reps 5] [--out DIR] [--partitions N]
                                           [--count 200] [--wait-idle S]

Issue #14's "Speed" must-show. Two scenes, written to DIR, from the first --count (200)
spheres of data/bench/spheres300.json (unit cube, h 0.02, one level):
  A  the spheres as analytic `sphere` inclusions;
  B  the same spheres as exact rational NURBS spheres: the `nurbs_surface` entry of
     data/shapes/nurbs_sphere.json (8 x 4 biquadratic rational patches of the unit sphere)
     with "scale": radius and "translate": centre, same phase and levels.
Both are meshed with `cisamr mesh SCENE -o OUT.vtu --report R.json -q` (and --partitions N
when given), alternately A B A B ... for --reps pairs; the two runs of a pair are back to back,
so a disturbance hits both or few.

Per run: the whole command's wall time and peak RSS (/usr/bin/time), the report's tetrahedra
("elements"), checksum, per-phase element counts and measures, and its phase timings
(timings_s, each phase's "max"). "other" is the report's total minus the listed phases: run
sequentially, the oracle's construction (for B the NURBS bodies: Bezier extraction,
tessellation, BVH) and the remaining bookkeeping (with --partitions the report lists "oracle",
"partition", "ghost", "merge" apart); "outside" is the command's wall time minus the report's total (process
start, reading and parsing the scene). Times are medians over the reps; B / A is the median of
the pairs' own ratios. tets/s divides the tetrahedra by the median wall time of the whole
command. The two meshes must have the same tetrahedron count within 0.5 % (a warning
otherwise). Writes DIR/nurbs_cost.md (the table) and DIR/nurbs_cost.json.
Run it on an idle machine: timings taken while something else compiles are worthless
(--wait-idle S holds each pair until nothing else runs, for S seconds at most).
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

PHASES = ["samr", "radapt", "faceswap", "subdivide", "assemble", "quality", "write"]
NOT_PHASES = ["total"]


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode not in (0, 3):  # 3: written, above the bound (reported, not fatal here)
        sys.exit(f"nurbs_cost: {' '.join(cmd)} failed ({r.returncode}):\n{r.stderr}")
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


def make_scenes(repo, out, count):
    base = json.load(open(os.path.join(repo, "data/bench/spheres300.json")))
    nurbs = json.load(open(os.path.join(repo, "data/shapes/nurbs_sphere.json")))
    assert nurbs["shape"] == "nurbs_surface"
    spheres = [i for i in base["inclusions"] if i["shape"] == "sphere"][:count]
    if len(spheres) < count:
        sys.exit(f"nurbs_cost: spheres300.json holds only {len(spheres)} spheres")
    a = dict(base, inclusions=spheres)
    b_inc = []
    for s in spheres:
        e = {k: v for k, v in s.items() if k not in ("shape", "center", "radius")}  # phase, levels, ...
        e.update(shape="nurbs_surface", scale=s["radius"], translate=s["center"], patches=nurbs["patches"])
        b_inc.append(e)
    b = dict(base, inclusions=b_inc)
    paths = {"A": os.path.join(out, "spheres_analytic.json"), "B": os.path.join(out, "spheres_nurbs.json")}
    json.dump(a, open(paths["A"], "w"), indent=1)
    json.dump(b, open(paths["B"], "w"))
    return paths


def mesh_once(cisamr, scene, out, tag, partitions):
    report = os.path.join(out, tag + ".report.json")
    target = os.path.join(out, tag + ".vtu")
    cmd = [cisamr, "mesh", scene, "-o", target, "--report", report, "-q"]
    if partitions:
        cmd += ["--partitions", str(partitions)]
    r = run(["/usr/bin/time", "-f", "TIME %e %M %U %S"] + cmd)
    line = [l for l in r.stderr.splitlines() if l.startswith("TIME ")][-1].split()
    j = json.load(open(report))
    t = {k: v["max"] for k, v in j["timings_s"].items()}
    listed = {k: v for k, v in t.items() if k not in NOT_PHASES}
    rec = {
        "elements": j["elements"],
        "nodes": j["nodes"],
        "checksum": j["checksum"],
        "phase_figures": [(p["id"], p["elements"], p["measure"]) for p in j["phases"]],
        "ar_max": j["aspect_ratio"]["max"],
        "wall_s": float(line[1]),
        "rss_kb": int(line[2]),
        "cpu_s": float(line[3]) + float(line[4]),
        "total_s": j["total_s"],
        "phases": listed,
        "other_s": j["total_s"] - sum(listed.values()),
        "outside_s": float(line[1]) - j["total_s"],
    }
    os.remove(target)
    return rec


def med(values):
    return statistics.median(list(values))


def summary(recs):
    shown = PHASES + sorted({p for r in recs for p in r["phases"]} - set(PHASES))
    return {
        "elements": sorted({r["elements"] for r in recs}),
        "nodes": sorted({r["nodes"] for r in recs}),
        "checksums": sorted({r["checksum"] for r in recs}),
        "phase_figures": recs[0]["phase_figures"],
        "ar_max": max(r["ar_max"] for r in recs),
        "wall_s": med(r["wall_s"] for r in recs),
        "wall_s_min": min(r["wall_s"] for r in recs),
        "cpu_s": med(r["cpu_s"] for r in recs),
        "total_s": med(r["total_s"] for r in recs),
        "phases": {p: med(r["phases"].get(p, 0) for r in recs) for p in shown},
        "reported": sorted({p for r in recs for p in r["phases"]}),
        "other_s": med(r["other_s"] for r in recs),
        "outside_s": med(r["outside_s"] for r in recs),
        "rss_kb": med(r["rss_kb"] for r in recs),
        "runs_wall_s": [r["wall_s"] for r in recs],
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("cisamr")
    ap.add_argument("--reps", type=int, default=5, help="A/B pairs (default 5)")
    ap.add_argument("--out", help="folder for the scenes, reports and tables (default: a new temp folder)")
    ap.add_argument("--partitions", type=int, default=0, metavar="N", help="mesh both with --partitions N")
    ap.add_argument("--count", type=int, default=200, help="spheres taken from spheres300.json (default 200)")
    ap.add_argument("--wait-idle", type=float, default=0, metavar="S",
                    help="before each A/B pair wait up to S seconds for the machine to be idle "
                         "(under 10 %% of its CPUs busy over 1 s); pairs started busy are counted")
    a = ap.parse_args()
    cisamr = os.path.abspath(a.cisamr)
    if not os.access(cisamr, os.X_OK):
        sys.exit(f"nurbs_cost: {cisamr} is not an executable")
    repo = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    out = a.out or tempfile.mkdtemp(prefix="cisamr_nurbs_cost_")
    os.makedirs(out, exist_ok=True)
    scenes = make_scenes(repo, out, a.count)

    recs = {"A": [], "B": []}
    busy_pairs = 0
    for rep in range(a.reps):
        if a.wait_idle > 0 and not wait_idle(a.wait_idle):
            busy_pairs += 1
        for side in "AB":
            recs[side].append(mesh_once(cisamr, scenes[side], out, f"run-{side}", a.partitions))
        print(f"pair {rep + 1}/{a.reps}: A {recs['A'][-1]['wall_s']:.2f} s, B {recs['B'][-1]['wall_s']:.2f} s",
              file=sys.stderr)
    A, B = summary(recs["A"]), summary(recs["B"])
    pairs = list(zip(recs["A"], recs["B"]))
    ratio = lambda f: med(f(b) / f(a) for a, b in pairs if f(a) > 0)
    q = {"wall_s": ratio(lambda r: r["wall_s"]), "cpu_s": ratio(lambda r: r["cpu_s"]),
         "total_s": ratio(lambda r: r["total_s"]), "rss_kb": ratio(lambda r: r["rss_kb"])}

    ta, tb = A["elements"][0], B["elements"][0]
    phases = [p for p in A["phases"] if p in A["reported"] or p in B["reported"]]
    rows = [("tetrahedra", f"{ta:,}", f"{tb:,}", f"{tb / ta:.4f}"),
            ("nodes", f"{A['nodes'][0]:,}", f"{B['nodes'][0]:,}", f"{B['nodes'][0] / A['nodes'][0]:.4f}"),
            ("wall s, whole command, median (min)", f"{A['wall_s']:.2f} ({A['wall_s_min']:.2f})",
             f"{B['wall_s']:.2f} ({B['wall_s_min']:.2f})", f"**{q['wall_s']:.3f}**"),
            ("CPU s (user + system), median", f"{A['cpu_s']:.2f}", f"{B['cpu_s']:.2f}", f"{q['cpu_s']:.3f}"),
            ("tets / s (tets / median wall)", f"{ta / A['wall_s']:,.0f}", f"{tb / B['wall_s']:,.0f}",
             f"{(tb / B['wall_s']) / (ta / A['wall_s']):.3f}"),
            ("tets / CPU s", f"{ta / A['cpu_s']:,.0f}", f"{tb / B['cpu_s']:,.0f}",
             f"{(tb / B['cpu_s']) / (ta / A['cpu_s']):.3f}"),
            ("report total s", f"{A['total_s']:.3f}", f"{B['total_s']:.3f}", f"{q['total_s']:.3f}")]
    for p in phases:
        pa, pb = A["phases"][p], B["phases"][p]
        rows.append((f"  {p} s", f"{pa:.3f}", f"{pb:.3f}", f"{pb / pa:.3f}" if pa >= 0.005 else "–"))
    rows.append(("  other s (total − listed phases)", f"{A['other_s']:.3f}", f"{B['other_s']:.3f}",
                 f"{B['other_s'] / A['other_s']:.3f}" if A["other_s"] >= 0.005 else "–"))
    rows.append(("outside the report s (start, scene read)", f"{A['outside_s']:.2f}", f"{B['outside_s']:.2f}",
                 f"{B['outside_s'] / A['outside_s']:.2f}" if A["outside_s"] > 0.005 else "–"))
    rows.append(("peak RSS KB (MiB)", f"{A['rss_kb']:,.0f} ({A['rss_kb'] / 1024:.0f})",
                 f"{B['rss_kb']:,.0f} ({B['rss_kb'] / 1024:.0f})", f"**{q['rss_kb']:.3f}**"))
    rows.append(("peak RSS bytes / tet", f"{A['rss_kb'] * 1024 / ta:.0f}", f"{B['rss_kb'] * 1024 / tb:.0f}",
                 f"{(B['rss_kb'] / tb) / (A['rss_kb'] / ta):.3f}"))
    rows.append(("aspect ratio max", f"{A['ar_max']:.3f}", f"{B['ar_max']:.3f}", ""))
    title = (f"{a.count} spheres of spheres300, {a.reps} A/B pairs"
             + (f", --partitions {a.partitions}" if a.partitions else ", sequential"))
    table = [f"| {title} | A analytic `sphere` | B `nurbs_surface` | B / A |", "|---|---:|---:|---:|"]
    table += [f"| {r[0]} | {r[1]} | {r[2]} | {r[3]} |" for r in rows]

    notes = []
    if len(A["elements"]) > 1 or len(B["elements"]) > 1 or len(A["checksums"]) > 1 or len(B["checksums"]) > 1:
        notes.append(f"- WARNING: repeated runs gave different meshes (A {A['checksums']}, B {B['checksums']})")
    dev = abs(tb - ta) / ta
    if dev > 0.005:
        notes.append(f"- WARNING: the tetrahedron counts differ by {100 * dev:.2f} % (A {ta:,}, B {tb:,}), "
                     "over 0.5 %: the two meshes are not comparable")
    else:
        notes.append(f"- tetrahedra A {ta:,}, B {tb:,}: {100 * dev:.3f} % apart (within 0.5 %)")
    fa, fb = A["phase_figures"], B["phase_figures"]
    if [x[:2] for x in fa] == [x[:2] for x in fb]:
        worst = max(abs(x[2] - y[2]) / max(abs(x[2]), 1e-300) for x, y in zip(fa, fb))
        notes.append(f"- per-phase tetrahedra equal; per-phase volumes agree to {worst:.1e} (relative); "
                     f"checksums A {A['checksums'][0]}, B {B['checksums'][0]}")
    else:
        notes.append(f"- per-phase figures (id, tets, volume): A {fa}, B {fb}")
    notes.append("- B / A: median of the pairs' own ratios (times, RSS); the other ratios divide the medians")
    if a.wait_idle > 0:
        notes.append(f"- {busy_pairs} of {a.reps} pairs started while the machine was busy "
                     f"(after waiting {a.wait_idle:g} s)")
    notes.append(f"- runs, wall s: A {A['runs_wall_s']}, B {B['runs_wall_s']}")
    text = "\n".join(table + [""] + notes) + "\n"
    print(text)
    open(os.path.join(out, "nurbs_cost.md"), "w").write(text)
    json.dump({"A": A, "B": B, "B/A": q, "runs": recs, "partitions": a.partitions, "count": a.count},
              open(os.path.join(out, "nurbs_cost.json"), "w"), indent=1)
    print(f"nurbs_cost: scenes, reports and tables in {out}", file=sys.stderr)


if __name__ == "__main__":
    main()
