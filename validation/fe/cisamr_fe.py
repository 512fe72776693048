#!/usr/bin/python3
"""Linear-elastic CalculiX runs on a cisamr Abaqus mesh (validation/fe/README.md).

    cisamr_fe.py uniaxial MESH.inp (--material PHASE=E,NU ... | --materials M.json)
                 [--strain 1e-3] [--support rollers|corner0] [--thickness 1]
                 [--workdir DIR] [--json OUT] [--ccx ccx]

The mesh is *INCLUDEd unchanged; each phase ELSET gets its *MATERIAL and *SOLID SECTION
(2D: the thickness; CPS3/CPE3 in the mesh pick plane stress or strain). The loading goes
through the mesh's boundary sets only. Modes are functions writing the job's step
(`uniaxial_step`); a periodic homogenisation mode (unit strains through REF nodes) adds
one more next to it and reuses the rest. Standard library only; exit 2 on bad input.
"""
import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

FACES = ["XMIN", "XMAX", "YMIN", "YMAX", "ZMIN", "ZMAX"]
PLANE_TYPES = {"CPS3": "stress", "CPE3": "strain"}


class InputProblem(Exception):
    """Bad input: one line, exit status 2."""


# ---------------------------------------------------------------------------------- mesh

class Mesh:
    """What the runs need from a cisamr .inp: nodes, elements per phase ELSET, node sets."""

    def __init__(self):
        self.path = ""
        self.dim = 3
        self.element_type = ""
        self.nodes = {}       # id -> (x, y[, z])
        self.elsets = []      # phase ELSETs in file order: dicts name, id, full_name, elements
        self.nsets = {}       # name -> [node ids]


def data_lines(lines, start):
    """The data lines after keyword line `start`: (index past them, [fields per line])."""
    rows, i = [], start + 1
    while i < len(lines) and not lines[i].startswith("*"):
        fields = [f.strip() for f in lines[i].split(",") if f.strip()]
        if fields:
            rows.append(fields)
        i += 1
    # Comment lines (**) end the block too; they are skipped by the caller.
    return i, rows


def read_inp(path):
    try:
        with open(path, encoding="utf-8") as f:
            lines = [line.rstrip("\n") for line in f]
    except OSError as e:
        raise InputProblem(f"{path}: cannot read: {e.strerror}")
    mesh = Mesh()
    mesh.path = path
    phase_comment = None
    i = 0
    while i < len(lines):
        line = lines[i]
        upper = line.upper()
        comment = re.match(r"\*\* cisamr phase (\d+) (.*)$", line)
        if comment:
            phase_comment = (int(comment.group(1)), comment.group(2))
            i += 1
            continue
        if line.startswith("**") or not line.startswith("*"):
            i += 1
            continue
        params = dict(
            (p.split("=", 1)[0].strip().upper(), p.split("=", 1)[1].strip()) if "=" in p else (p.strip().upper(), "")
            for p in line[1:].split(",")[1:])
        keyword = line[1:].split(",")[0].strip().upper()
        i, rows = data_lines(lines, i)
        if keyword == "NODE":
            for r in rows:
                mesh.nodes[int(r[0])] = tuple(float(x) for x in r[1:])
        elif keyword == "ELEMENT":
            kind = params.get("TYPE", "").upper()
            if kind not in ("C3D4", "CPS3", "CPE3"):
                raise InputProblem(f"{path}: *ELEMENT TYPE={kind}: expected C3D4, CPS3 or CPE3 (a cisamr mesh)")
            if mesh.element_type and kind != mesh.element_type:
                raise InputProblem(f"{path}: *ELEMENT: mixed types {mesh.element_type} and {kind}")
            mesh.element_type = kind
            mesh.dim = 3 if kind == "C3D4" else 2
            name = params.get("ELSET", "")
            if not name:
                raise InputProblem(f"{path}: *ELEMENT: no ELSET (each phase needs its set)")
            pid, full = phase_comment if phase_comment else (len(mesh.elsets) + 1, name)
            mesh.elsets.append({"name": name, "id": pid, "full_name": full,
                                "elements": [[int(x) for x in r] for r in rows]})
            phase_comment = None
        elif keyword == "NSET":
            mesh.nsets[params.get("NSET", "").upper()] = [int(x) for r in rows for x in r]
    if not mesh.nodes or not mesh.elsets:
        raise InputProblem(f"{path}: no *NODE or *ELEMENT block")
    if "XMIN" not in mesh.nsets or "XMAX" not in mesh.nsets:
        raise InputProblem(f"{path}: *NSET XMIN/XMAX missing (a mesh written by cisamr mesh carries them)")
    return mesh


def measure(mesh, element, thickness):
    """Volume of a tetrahedron, or area × thickness of a triangle."""
    p = [mesh.nodes[n] for n in element[1:]]
    if mesh.dim == 2:
        return 0.5 * abs((p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0])) * thickness
    u, v, w = ([p[k][d] - p[0][d] for d in range(3)] for k in (1, 2, 3))
    return abs(u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
               + u[2] * (v[0] * w[1] - v[1] * w[0])) / 6.0


def box_of(mesh):
    lo = [min(p[d] for p in mesh.nodes.values()) for d in range(mesh.dim)]
    hi = [max(p[d] for p in mesh.nodes.values()) for d in range(mesh.dim)]
    return lo, hi


# ----------------------------------------------------------------------------- materials

def parse_material(text):
    """'PHASE=E,NU' -> (PHASE, {'E': E, 'nu': NU})."""
    m = re.match(r"^([^=]+)=([^,]+),([^,]+)$", text)
    if not m:
        raise InputProblem(f"--material {text}: expected PHASE=E,NU (PHASE: a phase name or id)")
    try:
        return m.group(1).strip(), {"E": float(m.group(2)), "nu": float(m.group(3))}
    except ValueError:
        raise InputProblem(f"--material {text}: E and NU must be numbers")


def read_materials(path):
    try:
        with open(path, encoding="utf-8") as f:
            data = json.load(f)
    except (OSError, ValueError) as e:
        raise InputProblem(f"{path}: cannot read materials: {e}")
    if not isinstance(data, dict):
        raise InputProblem(f"{path}: expected an object {{\"PHASE\": {{\"E\": ..., \"nu\": ...}}}}")
    out = {}
    for key, value in data.items():
        if not isinstance(value, dict) or "E" not in value or "nu" not in value:
            raise InputProblem(f"{path}: {key}: expected {{\"E\": number, \"nu\": number}}")
        out[str(key)] = {"E": float(value["E"]), "nu": float(value["nu"])}
    return out


def assign_materials(mesh, given):
    """Per phase ELSET, its material: looked up by ELSET name, full phase name or id."""
    out = []
    for s in mesh.elsets:
        keys = [s["name"], s["full_name"], str(s["id"])]
        found = [given[k] for k in keys if k in given]
        if not found:
            lowered = {k.lower(): v for k, v in given.items()}
            found = [lowered[k.lower()] for k in keys if k.lower() in lowered]
        if not found:
            raise InputProblem(f"{mesh.path}: phase {s['id']} '{s['full_name']}' (ELSET {s['name']}): no material given")
        mat = found[0]
        if not (mat["E"] > 0 and -1 < mat["nu"] < 0.5):
            raise InputProblem(f"material of phase '{s['full_name']}': need E > 0 and -1 < nu < 0.5")
        out.append(mat)
    return out


def in_plane_modulus(mesh, mat):
    """The modulus a uniaxial in-plane stress sees: E, or E/(1-nu^2) in plane strain."""
    return mat["E"] / (1 - mat["nu"] ** 2) if PLANE_TYPES.get(mesh.element_type) == "strain" else mat["E"]


# ------------------------------------------------------------------------------------ job

def model_text(mesh, materials, thickness, include_name):
    # The mesh brings the *HEADING (ccx accepts one).
    lines = [f"** cisamr_fe on {os.path.basename(mesh.path)}", f"*INCLUDE, INPUT={include_name}"]
    for k, (s, mat) in enumerate(zip(mesh.elsets, materials)):
        lines += [f"*MATERIAL, NAME=MAT{k + 1}", "*ELASTIC", f"{mat['E']!r}, {mat['nu']!r}",
                  f"*SOLID SECTION, ELSET={s['name']}, MATERIAL=MAT{k + 1}"]
        if mesh.dim == 2:
            lines.append(f"{thickness!r}")
    return lines


def uniaxial_step(mesh, strain, support, length):
    """XMAX pulled by strain·length along x. Supports: `rollers` (XMIN in x, YMIN in y,
    ZMIN in z) or `corner0` (XMIN in x, CORNER0 in the other directions, and in 3D the
    XMIN∩YMIN edge in y against the rotation about x). Both admit the homogeneous
    uniaxial-stress solution of a single material."""
    lines = []
    if support == "rollers":
        needed = ["YMIN"] + (["ZMIN"] if mesh.dim == 3 else [])
        for name in needed:
            if name not in mesh.nsets:
                raise InputProblem(f"{mesh.path}: *NSET {name} missing: use --support corner0")
        fixes = [("XMIN", 1), ("YMIN", 2)] + ([("ZMIN", 3)] if mesh.dim == 3 else [])
    else:
        if "CORNER0" not in mesh.nsets:
            raise InputProblem(f"{mesh.path}: no CORNER0 (a void covers the min corner): use --support rollers")
        fixes = [("XMIN", 1), ("CORNER0", 2)]
        if mesh.dim == 3:
            edge = sorted(set(mesh.nsets["XMIN"]) & set(mesh.nsets.get("YMIN", [])))
            if not edge:
                raise InputProblem(f"{mesh.path}: XMIN and YMIN share no node: use --support rollers")
            lines += ["*NSET, NSET=XMIN_YMIN"] + [", ".join(map(str, edge[i:i + 16])) for i in range(0, len(edge), 16)]
            fixes += [("CORNER0", 3), ("XMIN_YMIN", 2)]
    lines += ["*STEP", "*STATIC", "*BOUNDARY"]
    lines += [f"{name}, {dof}, {dof}, 0" for name, dof in fixes]
    lines += [f"XMAX, 1, 1, {strain * length!r}",
              "*NODE PRINT, NSET=XMAX, TOTALS=ONLY", "RF"]
    for s in mesh.elsets:
        lines += [f"*EL PRINT, ELSET={s['name']}", "E"]
    lines.append("*END STEP")
    return lines


def run_ccx(ccx, workdir, job_lines):
    with open(os.path.join(workdir, "job.inp"), "w", encoding="utf-8") as f:
        f.write("\n".join(job_lines) + "\n")
    env = dict(os.environ, OMP_NUM_THREADS=os.environ.get("OMP_NUM_THREADS", "1"))
    start = time.monotonic()
    done = subprocess.run([ccx, "-i", "job"], cwd=workdir, env=env, capture_output=True, text=True)
    seconds = time.monotonic() - start
    dat = os.path.join(workdir, "job.dat")
    log = done.stdout + done.stderr
    if done.returncode != 0 or "*ERROR" in log or not os.path.exists(dat):
        lines = log.splitlines()
        errors = [i for i, line in enumerate(lines) if "*ERROR" in line]
        tail = "\n".join(lines[i + k].strip() for i in errors[:5] for k in range(3) if i + k < len(lines))
        raise RuntimeError(f"ccx failed (exit {done.returncode}) in {workdir}:\n{tail}")
    with open(dat, encoding="utf-8") as f:
        return f.read(), seconds


def parse_dat(text):
    """Total forces per node set and strains (elem, ip, exx, eyy, ezz, exy, exz, eyz)."""
    forces, strains, block = {}, [], None
    for line in text.splitlines():
        head = re.match(r"\s*total force \(fx,fy,fz\) for set (\S+)", line)
        if head:
            block = ("force", head.group(1).upper())
            continue
        if re.match(r"\s*strains \(elem", line):
            block = ("strain", None)
            continue
        fields = line.split()
        if not fields or block is None:
            continue
        try:
            values = [float(x) for x in fields]
        except ValueError:
            block = None
            continue
        if block[0] == "force":
            forces[block[1]] = values[:3]
            block = None
        else:
            strains.append(values)
    return forces, strains


# ---------------------------------------------------------------------------------- modes

def strain_statistics(strains):
    names = ["exx", "eyy", "ezz", "exy", "exz", "eyz"]
    stats = {}
    for k, name in enumerate(names):
        column = [row[2 + k] for row in strains]
        mean = sum(column) / len(column)
        stats[name] = {"mean": mean, "min": min(column), "max": max(column),
                       "std": math.sqrt(sum((x - mean) ** 2 for x in column) / len(column))}
    scale = abs(stats["exx"]["mean"]) or 1.0
    stats["max_deviation_over_exx"] = max(
        max(abs(row[2 + k] - stats[name]["mean"]) for row in strains) for k, name in enumerate(names)) / scale
    return stats


def uniaxial(args):
    mesh = read_inp(args.mesh)
    given = {}
    if args.materials:
        given.update(read_materials(args.materials))
    for text in args.material or []:
        key, mat = parse_material(text)
        given[key] = mat
    materials = assign_materials(mesh, given)
    if not args.strain != 0:
        raise InputProblem("--strain: must not be 0")
    thickness = args.thickness if mesh.dim == 2 else 1.0
    lo, hi = box_of(mesh)
    length = hi[0] - lo[0]
    area = thickness
    for d in range(1, mesh.dim):
        area *= hi[d] - lo[d]
    box_volume = length * area

    volumes = [sum(measure(mesh, e, thickness) for e in s["elements"]) for s in mesh.elsets]
    fractions = [v / box_volume for v in volumes]
    moduli = [in_plane_modulus(mesh, m) for m in materials]
    voigt = sum(f * e for f, e in zip(fractions, moduli))
    solid = sum(fractions)
    reuss = 1.0 / sum(f / e for f, e in zip(fractions, moduli)) if abs(solid - 1) < 1e-9 else 0.0

    workdir = args.workdir or tempfile.mkdtemp(prefix="cisamr_fe_")
    os.makedirs(workdir, exist_ok=True)
    include_name = "mesh.inp"  # ccx lines are limited to 132 characters: no long paths
    shutil.copyfile(args.mesh, os.path.join(workdir, include_name))
    job = model_text(mesh, materials, thickness, include_name) + uniaxial_step(mesh, args.strain, args.support, length)
    try:
        dat, seconds = run_ccx(args.ccx, workdir, job)
    finally:
        if not args.workdir:
            shutil.rmtree(workdir, ignore_errors=True)
    forces, strains = parse_dat(dat)
    if "XMAX" not in forces or not strains:
        raise RuntimeError("ccx wrote no reaction force on XMAX or no strains")
    stress = forces["XMAX"][0] / area
    result = {
        "mesh": args.mesh, "dimension": mesh.dim, "element_type": mesh.element_type,
        "plane": PLANE_TYPES.get(mesh.element_type, ""), "support": args.support,
        "strain": args.strain, "length": length, "area": area, "thickness": thickness if mesh.dim == 2 else None,
        "elements": sum(len(s["elements"]) for s in mesh.elsets),
        "phases": [{"id": s["id"], "name": s["full_name"], "elset": s["name"], "E": m["E"], "nu": m["nu"],
                    "volume": v, "fraction": f} for s, m, v, f in zip(mesh.elsets, materials, volumes, fractions)],
        "reaction_xmax": forces["XMAX"], "stress": stress,
        "apparent_modulus": stress / args.strain,
        "voigt": voigt, "reuss": reuss,
        "strains": strain_statistics(strains), "integration_points": len(strains),
        "ccx_seconds": seconds,
    }
    return result


def print_uniaxial(r, out):
    kind = f"{r['dimension']}D {r['element_type']}" + (f" (plane {r['plane']})" if r["plane"] else "")
    print(f"{r['mesh']}: {kind}, {r['elements']} elements; ccx {r['ccx_seconds']:.2f} s", file=out)
    for p in r["phases"]:
        print(f"  phase {p['id']} {p['name']}: E {p['E']:g}, nu {p['nu']:g}, volume fraction {p['fraction']:.6f}", file=out)
    print(f"uniaxial x, strain {r['strain']:g}, supports {r['support']}: "
          f"apparent E = {r['apparent_modulus']:.8g} (Voigt {r['voigt']:.8g}, Reuss {r['reuss']:.8g})", file=out)
    s = r["strains"]
    for name in ("exx", "eyy", "ezz", "exy", "exz", "eyz"):
        c = s[name]
        print(f"  {name}: mean {c['mean']: .6e}  min {c['min']: .6e}  max {c['max']: .6e}  std {c['std']:.3e}", file=out)
    print(f"  largest deviation from the mean strain / |mean exx|: {s['max_deviation_over_exx']:.3e} "
          f"({r['integration_points']} integration points)", file=out)


def main(argv):
    parser = argparse.ArgumentParser(description="Linear-elastic CalculiX runs on a cisamr .inp mesh")
    modes = parser.add_subparsers(dest="mode", required=True)
    u = modes.add_parser("uniaxial", help="uniaxial test through the boundary sets: apparent Young's modulus")
    u.add_argument("mesh", help="a .inp written by cisamr mesh")
    u.add_argument("--material", action="append", metavar="PHASE=E,NU",
                   help="material of a phase (name, ELSET name or id); repeat per phase")
    u.add_argument("--materials", metavar="M.json", help='{"PHASE": {"E": ..., "nu": ...}, ...}')
    u.add_argument("--strain", type=float, default=1e-3, help="imposed strain along x (default 1e-3)")
    u.add_argument("--support", choices=["rollers", "corner0"], default="rollers",
                   help="rollers: XMIN/YMIN/ZMIN each fixed normal to itself (default); corner0: XMIN in x, "
                        "CORNER0 in the others (3D: plus the XMIN-YMIN edge in y)")
    u.add_argument("--thickness", type=float, default=1.0, help="2D: section thickness (default 1)")
    u.add_argument("--workdir", help="keep the CalculiX job and its output here (default: a temporary folder)")
    u.add_argument("--json", metavar="OUT", help="write the results as JSON ('-': standard output)")
    u.add_argument("--ccx", default="ccx", help="the CalculiX executable (default ccx)")
    return run_tool("cisamr_fe", parser.parse_args(argv), uniaxial, print_uniaxial)


def run_tool(name, args, solve, print_result):
    """The command-line tail the FE tools share: CalculiX present, solve, print the result
    (to standard error when the JSON goes to standard output), write the JSON. Exit codes:
    2 bad input (one line), 1 a failed solve, 0 done."""
    if shutil.which(args.ccx) is None:
        print(f"{name}: error: {args.ccx}: CalculiX not found (Debian: apt-get install calculix-ccx)", file=sys.stderr)
        return 2
    try:
        result = solve(args)
    except InputProblem as e:
        print(f"{name}: error: {e}", file=sys.stderr)
        return 2
    except RuntimeError as e:
        print(f"{name}: {e}", file=sys.stderr)
        return 1
    print_result(result, sys.stderr if args.json == "-" else sys.stdout)
    if args.json:
        text = json.dumps(result, indent=1) + "\n"
        if args.json == "-":
            sys.stdout.write(text)
        else:
            with open(args.json, "w", encoding="utf-8") as f:
                f.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
