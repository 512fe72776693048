#!/usr/bin/env python3
"""The paper's four examples (data/paper/e1..e4) meshed on 1 and 2 ranks, in one table.

    python3 validation/paper/run_paper.py BUILD_DIR [--out DIR] [--only e1,e3] [--ranks 1,2]
                                          [--e4-h 8] [--h e1=0.5,e2=0.5] [--stream e4] [--no-certify]
                                          [--table TABLE.md]

For each example: `cisamr pack SPEC -o SCENE`, then per rank count R

    /usr/bin/time -f "%e %M" cisamr mesh SCENE -o eK_1.vtu --report eK_1.json -q         (R = 1)
    /usr/bin/time -f "%e %M" mpiexec -n R cisamr mesh SCENE -o eK_R.pvtu --report ... -q  (R > 1)

and `cisamr certify MESH --scene SCENE --json ...` on the first mesh made (a .pvtu is
certified piece by piece, in bounded memory). The table gives
the elements, the whole command's wall time per rank count, each rank's peak resident
memory (the report's `peak_rss_bytes`, which every rank measures itself: /usr/bin/time
under mpiexec sees only the launcher), bytes per element, the parallel efficiency
t(1) / (R t(R)), the worst aspect ratio, the certificate and whether the order-free
checksums of all rank counts agree (the same mesh). Markdown on standard output and, with
--table, in a file.

--h NAME=H,... sets an example's background element size (the spec's by default: E1 and E2
at h = 1 give 9.7 M and 4.3 M triangles; h = 0.5 gives the paper's counts).
E4: --e4-h sets its background size (default 8: about 90 M tetrahedra in memory; 800/144
gives the paper's count, about 186 M, which needs --stream e4) and meshes it with
--extra-levels 0, as validation/paper3 does. --stream EXAMPLES runs those with
`--stream` (one piece per partition, 8 partitions per rank unless their share would not
fit in memory): their memory is one partition per rank.
Each run is a separate process: a failure (exit code, out of memory) is reported in its row
and the others go on.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = {
    "e1": ("e1_sic_particles.json", "E1 SiC/Al particles (2D)"),
    "e2": ("e2_corrosion_pits.json", "E2 corrosion pits (2D)"),
    "e3": ("e3_cross_ply.json", "E3 cross-ply CFRP (3D)"),
    "e4": ("e4_silica_spheres.json", "E4 silica/epoxy (3D)"),
}


def timed(command, log):
    """Runs `command` under /usr/bin/time; returns (exit code, wall s, max RSS KiB of the process /usr/bin/time saw)."""
    stamp = log.with_suffix(".time")
    full = ["/usr/bin/time", "-o", str(stamp), "-f", "%e %M"] + command
    with open(log, "w") as out:
        code = subprocess.call(full, stdout=out, stderr=subprocess.STDOUT)
    try:
        wall, rss = stamp.read_text().split()[-2:]
        return code, float(wall), int(rss)
    except (OSError, ValueError):
        return code, float("nan"), 0


def mpiexec(ranks):
    launcher = ["mpiexec", "-n", str(ranks), "--oversubscribe"]
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        launcher.append("--allow-run-as-root")
    return launcher


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("build", help="build directory holding bin/cisamr (Release)")
    parser.add_argument("--out", default=None, help="working directory (default: a new temporary one)")
    parser.add_argument("--only", default="e1,e2,e3,e4", help="comma-separated examples")
    parser.add_argument("--ranks", default="1,2", help="comma-separated rank counts (1 first)")
    parser.add_argument("--e4-h", type=float, default=8.0, help="E4's background element size (spec: 4)")
    parser.add_argument("--h", default="", help="background sizes, NAME=H,... (default: the specs')")
    parser.add_argument("--stream", default="", help="comma-separated examples to mesh with --stream")
    parser.add_argument("--no-certify", action="store_true", help="skip cisamr certify")
    parser.add_argument("--keep-meshes", action="store_true", help="keep the mesh files (large)")
    parser.add_argument("--table", default=None, help="also write the table to this file")
    args = parser.parse_args()

    cisamr = Path(args.build).resolve() / "bin" / "cisamr"
    if not cisamr.is_file():
        sys.exit(f"run_paper.py: no {cisamr}: build it first (ninja -C {args.build} cisamr)")
    out = Path(args.out) if args.out else Path(
        subprocess.check_output(["mktemp", "-d", "/tmp/cisamr-paper.XXXXXX"], text=True).strip())
    out.mkdir(parents=True, exist_ok=True)
    ranks = [int(r) for r in args.ranks.split(",")]
    if ranks[0] != 1:
        sys.exit("run_paper.py: --ranks must start with 1 (the efficiency and the certificate use it)")
    if any(r > 1 for r in ranks) and shutil.which("mpiexec") is None:
        sys.exit("run_paper.py: mpiexec not found (install OpenMPI or use --ranks 1)")

    rows = []
    for name in args.only.split(","):
        spec, title = EXAMPLES[name]
        scene = out / f"{name}.json"
        subprocess.check_call([str(cisamr), "pack", str(ROOT / "data" / "paper" / spec), "-o", str(scene), "-q"])
        extra = []
        sizes = dict(item.split("=") for item in args.h.split(",") if item)
        if name in sizes:
            s = json.loads(scene.read_text())
            extent = s["domain"]["max"][0] - s["domain"]["min"][0]
            s["mesh"]["h"] = extent / round(extent / float(sizes[name]))  # h must divide the domain
            scene.write_text(json.dumps(s))
        if name == "e4":
            s = json.loads(scene.read_text())
            s["mesh"]["h"] = 800 / round(800 / args.e4_h)  # h must divide the 800 µm cube
            scene.write_text(json.dumps(s))
            extra = ["--extra-levels", "0"]
        streamed = name in args.stream.split(",")
        row = {"name": name, "title": title + (", streamed" if streamed else ""), "runs": {}}
        for r in ranks:
            mesh = out / (f"{name}_1.vtu" if r == 1 and not streamed else f"{name}_{r}.pvtu")
            report = out / f"{name}_{r}-report.json"
            command = [str(cisamr), "mesh", str(scene), "-o", str(mesh), "--report", str(report), "-q"] + extra
            if streamed:
                command.append("--stream")
            if r > 1:
                command = mpiexec(r) + command
            print(f"== {name}, {r} rank(s): {' '.join(command)}", file=sys.stderr, flush=True)
            code, wall, rss_kib = timed(command, out / f"{name}_{r}.log")
            run = {"exit": code, "wall": wall, "time_rss": rss_kib * 1024}
            if code in (0, 3) and report.is_file():
                rep = json.loads(report.read_text())
                run.update(elements=rep["elements"], checksum=rep["checksum"], worst=rep["aspect_ratio"]["max"],
                           bound=rep["aspect_ratio"]["bound"], above=rep["aspect_ratio"]["above_bound"],
                           peak_max=rep["peak_rss_bytes"]["max"], peak_total=rep["peak_rss_bytes"]["total"])
            row["runs"][r] = run
            if code in (0, 3) and not args.no_certify and "certify" not in row:  # the first mesh made
                cert = out / f"{name}-certificate.json"
                print(f"== {name}: cisamr certify {mesh} --scene {scene}", file=sys.stderr, flush=True)
                t0 = time.monotonic()
                c = subprocess.call([str(cisamr), "certify", str(mesh), "--scene", str(scene), "--json", str(cert), "-q"],
                                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                row["certify"] = ("PASSED" if c == 0 else f"FAILED (exit {c})") + f", {time.monotonic() - t0:.0f} s"
            if not args.keep_meshes:
                for piece in [mesh] + sorted(out.glob(f"{name}_{r}_*.vtu")):
                    piece.unlink(missing_ok=True)
        rows.append(row)

    table = render(rows, ranks)
    print(table)
    if args.table:
        Path(args.table).write_text(table)
    print(f"outputs in {out}", file=sys.stderr)


def render(rows, ranks):
    mib = 1024.0 * 1024.0
    head = ["example", "elements"]
    for r in ranks:
        head += [f"{r} rank{'s' if r > 1 else ''}: time s", "peak MiB/rank", "B/element"]
        if r > 1:
            head.append("efficiency")
    head += ["worst aspect (bound)", "certify", "checksum equal"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for row in rows:
        runs = row["runs"]
        one = runs.get(1, {})
        cells = [row["title"], f"{one.get('elements', 0):,}" if "elements" in one else "-"]
        for r in ranks:
            run = runs.get(r, {})
            if "elements" not in run:
                cells += [f"exit {run.get('exit')}", "-", "-"] + (["-"] if r > 1 else [])
                continue
            cells += [f"{run['wall']:.1f}", f"{run['peak_max'] / mib:.0f}", f"{run['peak_total'] / run['elements']:.0f}"]
            if r > 1:
                eff = one.get("wall", float("nan")) / (r * run["wall"]) if "elements" in one else float("nan")
                cells.append(f"{eff:.2f}")
        cells.append(f"{one['worst']:.3f} ({one['bound']:g}, {one['above']} above)" if "worst" in one else "-")
        cells.append(row.get("certify", "-"))
        sums = {run.get("checksum") for run in runs.values()}
        cells.append(("yes " if len(sums) == 1 and None not in sums else "NO ") + (one.get("checksum") or ""))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
