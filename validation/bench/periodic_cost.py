#!/usr/bin/env python3
"""Cost of periodicity (not a test): the same scenes meshed with and without `periodic`.

    python3 validation/bench/periodic_cost.py BUILD/bin/cisamr [--reps 5] [--out DIR] [--ranks 2]

Cases (each a pair A = not periodic, B = periodic, runs interleaved A B A B ...):
  spheres300-inside  data/bench/spheres300.json as it is and with "periodic": true. No sphere
                     reaches a face, so the meshes have the same elements: what is left is
                     the price of the torus machinery itself (wrapping windows, canonical keys,
                     plane nodes, the writers' links).
  spheres300-packed  the same packing spec (300 spheres, r 0.03-0.06, unit cube, h 0.02)
                     packed with periodic false and true: spheres cross faces, edges and
                     corners in B, their images are meshed; compared per element.
  circles2000        2D: 2,000 circles of two phases (~30 % area) packed with periodic false
                     and true (`cisamr pack`), h 1, one level.
  rve3d              data/examples/rve3d.json clipped (A) and wrapped (B).
and, with --ranks R > 1, spheres300-packed under `mpiexec -n R` with 16 partitions (.pvtu
pieces): ghost cells meshed and the master exchange.

Per run: `cisamr mesh --report` phase times, the whole command's wall time and peak RSS
(/usr/bin/time). "mesh s" is the report's total minus read and write (the meshing itself:
oracle, stages and the quality pass); per-element figures divide by each run's own element
count. Medians over --reps runs. Peak RSS is the largest process's (one rank under mpiexec). Writes DIR/periodic_cost.md (the tables) and DIR/periodic_cost.json.
Run it on an idle machine: timings taken while something else compiles are worthless.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys

PHASES = ["oracle", "samr", "radapt", "faceswap", "subdivide", "assemble"]


def run(cmd, **kw):
    r = subprocess.run(cmd, capture_output=True, text=True, **kw)
    if r.returncode not in (0, 3):  # 3: written, above the bound (reported, not fatal here)
        sys.exit(f"periodic_cost: {' '.join(cmd)} failed ({r.returncode}):\n{r.stderr}")
    return r


def pack(cisamr, spec, path):
    spec_path = path + ".pack.json"
    json.dump(spec, open(spec_path, "w"), indent=1)
    run([cisamr, "pack", spec_path, "-o", path, "-q"])
    return path


def with_periodic(src, dst, periodic):
    scene = json.load(open(src))
    scene["domain"]["periodic"] = periodic
    for inc in scene["inclusions"]:  # STL paths stay valid from the new folder
        if "file" in inc and not os.path.isabs(inc["file"]):
            inc["file"] = os.path.join(os.path.dirname(os.path.abspath(src)), inc["file"])
    json.dump(scene, open(dst, "w"))
    return dst


def mesh_once(cisamr, scene, out, tag, ranks=1, partitions=0):
    report = os.path.join(out, tag + ".report.json")
    target = os.path.join(out, tag + (".pvtu" if partitions else ".vtu"))
    cmd = [cisamr, "mesh", scene, "-o", target, "--report", report, "-q"]
    if partitions:
        cmd += ["--partitions", str(partitions)]
    if ranks > 1:
        cmd = ["mpiexec", "--oversubscribe", "--allow-run-as-root", "-n", str(ranks)] + cmd
    timed = ["/usr/bin/time", "-f", "TIME %e %M"] + cmd
    r = run(timed)
    line = [l for l in r.stderr.splitlines() if l.startswith("TIME ")][-1].split()
    j = json.load(open(report))
    t = j["timings_s"]
    phase = {p: t[p]["max"] for p in PHASES if p in t}
    rec = {
        "elements": j["elements"],
        "nodes": j["nodes"],
        "wall_s": float(line[1]),
        "rss_mib": int(line[2]) / 1024,  # the largest process (one rank under mpiexec)
        "mesh_s": j["total_s"] - t.get("read", {"max": 0})["max"] - t.get("write", {"max": 0})["max"],
        "write_s": t.get("write", {"max": 0})["max"],
        "phases": phase,
        "images": j.get("periodic", {}).get("images", 0),
        "slaves": j.get("periodic", {}).get("slaves", 0),
        "exchange_s": j.get("periodic", {}).get("master_exchange_s"),
        "ghost_cells": sum(p.get("ghost_coarse_cells", 0) for p in j["partitions"]),
        "coarse_cells": j["algorithm"].get("coarse_cells", 0),
        "checksum": j["checksum"],
    }
    for f in [target] + [os.path.join(out, tag + f"_{k}.vtu") for k in range(ranks)]:
        if os.path.exists(f):
            os.remove(f)
    return rec


def median(recs, key):
    return statistics.median(key(r) for r in recs)


def summary(recs):
    return {
        "elements": recs[0]["elements"],
        "images": recs[0]["images"],
        "slaves": recs[0]["slaves"],
        "mesh_s": median(recs, lambda r: r["mesh_s"]),
        "wall_s": median(recs, lambda r: r["wall_s"]),
        "write_s": median(recs, lambda r: r["write_s"]),
        "rss_mib": median(recs, lambda r: r["rss_mib"]),
        "phases": {p: median(recs, lambda r: r["phases"].get(p, 0)) for p in PHASES},
        "exchange_s": recs[0]["exchange_s"] and median(recs, lambda r: r["exchange_s"] or 0),
        "ghost_cells": recs[0]["ghost_cells"],
        "checksums": sorted({r["checksum"] for r in recs}),
        "runs_mesh_s": [round(r["mesh_s"], 4) for r in recs],
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("cisamr")
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--out", default="/tmp/cisamr_periodic_cost")
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--only", help="comma-separated case names")
    a = ap.parse_args()
    cisamr = os.path.abspath(a.cisamr)
    repo = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    os.makedirs(a.out, exist_ok=True)
    o = lambda name: os.path.join(a.out, name)

    spheres_spec = json.load(open(os.path.join(repo, "data/bench/spheres300.pack.json")))
    circles_spec = {
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

    def packed(spec, name, periodic):
        s = json.loads(json.dumps(spec))
        s["domain"]["periodic"] = periodic
        return pack(cisamr, s, o(name))

    cases = {
        "spheres300-inside": lambda: (
            with_periodic(os.path.join(repo, "data/bench/spheres300.json"), o("s300-a.json"), False),
            with_periodic(os.path.join(repo, "data/bench/spheres300.json"), o("s300-b.json"), True), 1, 0),
        "spheres300-packed": lambda: (packed(spheres_spec, "s300p-a.json", False),
                                      packed(spheres_spec, "s300p-b.json", True), 1, 0),
        "circles2000": lambda: (packed(circles_spec, "c2000-a.json", False),
                                packed(circles_spec, "c2000-b.json", True), 1, 0),
        "rve3d": lambda: (with_periodic(os.path.join(repo, "data/examples/rve3d.json"), o("rve-a.json"), False),
                          with_periodic(os.path.join(repo, "data/examples/rve3d.json"), o("rve-b.json"), True), 1, 0),
    }
    if a.ranks > 1:
        cases[f"spheres300-packed-{a.ranks}ranks-16parts"] = lambda: (
            o("s300p-a.json"), o("s300p-b.json"), a.ranks, 16)
    if a.only:
        cases = {k: v for k, v in cases.items() if k in a.only.split(",")}

    results = {}
    for name, make in cases.items():
        scene_a, scene_b, ranks, parts = make()
        recs = {"A": [], "B": []}
        for rep in range(a.reps):
            for side, scene in (("A", scene_a), ("B", scene_b)):
                recs[side].append(mesh_once(cisamr, scene, a.out, f"run-{side}", ranks, parts))
        results[name] = {side: summary(r) for side, r in recs.items()}
        print(f"{name}: done", file=sys.stderr)

    lines = ["| case | mode | elements | images | slaves | mesh s (median) | µs / element | ratio per element "
             "| " + " | ".join(PHASES) + " | write s | peak RSS MiB | bytes / element |",
             "|---|---|---:|---:|---:|---:|---:|---:|" + "---:|" * len(PHASES) + "---:|---:|---:|"]
    for name, r in results.items():
        per = {s: r[s]["mesh_s"] / r[s]["elements"] * 1e6 for s in "AB"}
        for s, mode in (("A", "clipped"), ("B", "periodic")):
            x = r[s]
            ratio = "1" if s == "A" else f"{per['B'] / per['A']:.3f}"
            lines.append(
                f"| {name} | {mode} | {x['elements']:,} | {x['images']} | {x['slaves']} | {x['mesh_s']:.3f} "
                f"| {per[s]:.3f} | {ratio} | " + " | ".join(f"{x['phases'][p]:.3f}" for p in PHASES) +
                f" | {x['write_s']:.3f} | {x['rss_mib']:.0f} | {x['rss_mib'] * 2**20 / x['elements']:.0f} |")
    extra = []
    for name, r in results.items():
        b = r["B"]
        if b["exchange_s"] is not None or b["ghost_cells"]:
            extra.append(f"- {name}: ghost cells meshed {r['A']['ghost_cells']:,} (clipped) vs "
                         f"{b['ghost_cells']:,} (periodic); master exchange {b['exchange_s'] or 0:.4f} s")
        if len(b["checksums"]) > 1 or len(r["A"]["checksums"]) > 1:
            extra.append(f"- {name}: WARNING: repeated runs gave different meshes")
    text = "\n".join(lines + [""] + extra) + "\n"
    print(text)
    open(o("periodic_cost.md"), "w").write(text)
    json.dump(results, open(o("periodic_cost.json"), "w"), indent=1)


if __name__ == "__main__":
    main()
