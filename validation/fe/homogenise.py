#!/usr/bin/python3
"""Periodic homogenisation with CalculiX on a periodic cisamr Abaqus mesh (validation/fe/README.md).

    homogenise.py MESH.inp (--material PHASE=E,NU ... | --materials M.json | --scene SCENE.json)
                  [--strain 1e-3] [--thickness 1] [--workdir DIR] [--json OUT] [--ccx ccx]

A periodic mesh written by `cisamr mesh -o MESH.inp` carries its constraints: one REF node
per axis (REF_X, REF_Y, REF_Z) and one *EQUATION per slave dof, u_s = u_m + sum of u_REF_a
over the axes along which s is shifted. Prescribing u(REF_a) = E . (T_a e_a) imposes the
macroscopic strain E; CORNER0 is fixed against rigid translation. Each of the 3 (2D) or 6
(3D) unit strains is one CalculiX run; the volume average of the element stresses over the
box (voids count as zero stress) gives one column of the effective stiffness matrix, in
Voigt order 11, 22, (33,) (23, 13,) 12 with engineering shear strains. Printed with it: the
Voigt (sum f_i C_i) and Reuss ((sum f_i S_i)^-1, zero with voids) bounds from the phase
volume fractions of the mesh, and per run how far the element strains stray from the
imposed one (zero for a single material: the uniform strain is exact).

Materials by phase (name, ELSET label or id): --material, --materials, or the phases of
--scene when they carry E and nu ("E"/"nu" or "material": {"E", "nu"}; cisamr-scene/1 has
no such fields yet, so today they come from the command line). Standard library only
(it reuses cisamr_fe.py); exit 2 on bad input.
"""
import argparse
import json
import math
import os
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cisamr_fe as fe  # noqa: E402

AXES = "XYZ"


# ------------------------------------------------------------------------- small linear algebra

def inverse(a):
    n = len(a)
    m = [list(map(float, row)) + [1.0 if i == j else 0.0 for j in range(n)] for i, row in enumerate(a)]
    for c in range(n):
        p = max(range(c, n), key=lambda r: abs(m[r][c]))
        if m[p][c] == 0:
            raise ZeroDivisionError("singular matrix")
        m[c], m[p] = m[p], m[c]
        pivot = m[c][c]
        m[c] = [x / pivot for x in m[c]]
        for r in range(n):
            if r != c and m[r][c] != 0:
                f = m[r][c]
                m[r] = [x - f * y for x, y in zip(m[r], m[c])]
    return [row[n:] for row in m]


def symmetric_eigenvalues(a):
    """Jacobi rotations: the eigenvalues of a small symmetric matrix, ascending."""
    n = len(a)
    m = [list(map(float, row)) for row in a]
    for _ in range(100):
        off = max((abs(m[i][j]), i, j) for i in range(n) for j in range(n) if i < j) if n > 1 else (0, 0, 0)
        if off[0] <= 1e-15 * max(1e-300, max(abs(m[i][i]) for i in range(n))):
            break
        _, p, q = off
        theta = 0.5 * math.atan2(2 * m[p][q], m[q][q] - m[p][p])
        c, s = math.cos(theta), math.sin(theta)
        for k in range(n):
            mkp, mkq = m[k][p], m[k][q]
            m[k][p], m[k][q] = c * mkp - s * mkq, s * mkp + c * mkq
        for k in range(n):
            mpk, mqk = m[p][k], m[q][k]
            m[p][k], m[q][k] = c * mpk - s * mqk, s * mpk + c * mqk
    return sorted(m[i][i] for i in range(n))


def stiffness(dim, plane, mat):
    """Isotropic stiffness in Voigt notation (engineering shear): 3D 6x6, 2D 3x3 (plane strain
    or plane stress)."""
    E, nu = mat["E"], mat["nu"]
    if dim == 2 and plane == "stress":
        c = E / (1 - nu * nu)
        return [[c, c * nu, 0], [c * nu, c, 0], [0, 0, c * (1 - nu) / 2]]
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    if dim == 2:
        return [[lam + 2 * mu, lam, 0], [lam, lam + 2 * mu, 0], [0, 0, mu]]
    c = [[0.0] * 6 for _ in range(6)]
    for i in range(3):
        for j in range(3):
            c[i][j] = lam + (2 * mu if i == j else 0)
        c[i + 3][i + 3] = mu
    return c


# ---------------------------------------------------------------------------- periodic mesh

def voigt_pairs(dim):
    """Voigt components as tensor index pairs: 2D 11, 22, 12; 3D 11, 22, 33, 23, 13, 12."""
    return [(0, 0), (1, 1), (0, 1)] if dim == 2 else [(0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)]


def read_constraints(path):
    """The slaves of the mesh's *EQUATIONs (their first terms)."""
    slaves, expect = set(), 0
    in_equation = False
    with open(path, encoding="utf-8") as f:
        for line in f:
            if line.startswith("**"):
                continue
            if line.startswith("*"):
                in_equation = line[1:].split(",")[0].strip().upper() == "EQUATION"
                expect = 0
                continue
            if not in_equation or not line.strip():
                continue
            fields = [x.strip() for x in line.split(",") if x.strip()]
            if expect == 0:
                expect = int(fields[0])
                first = True
                continue
            if first:
                slaves.add(int(fields[0]))
                first = False
            expect -= len(fields) // 3
    return slaves


def periodic_setup(mesh):
    refs = {}
    for a in range(mesh.dim):
        ids = mesh.nsets.get("REF_" + AXES[a], [])
        if len(ids) != 1:
            missing = [AXES[k] for k in range(mesh.dim) if len(mesh.nsets.get("REF_" + AXES[k], [])) != 1]
            raise fe.InputProblem(f"{mesh.path}: no REF node along {', '.join(missing)}: homogenisation needs a mesh "
                                  f"periodic along every axis (domain.periodic: true)")
        refs[a] = ids[0]
    corner = mesh.nsets.get("CORNER0", [])
    return refs, corner[0] if corner else None


def case_job(mesh, refs, fixed, strain_tensor, lo, hi):
    lines = ["*STEP", "*STATIC", "*BOUNDARY"]
    lines += [f"{fixed}, {d}, {d}, 0" for d in range(1, mesh.dim + 1)]
    for a, ref in refs.items():
        period = hi[a] - lo[a]
        for i in range(mesh.dim):
            lines.append(f"{ref}, {i + 1}, {i + 1}, {strain_tensor[i][a] * period!r}")
    for s in mesh.elsets:
        lines += [f"*EL PRINT, ELSET={s['name']}", "S, E"]
    lines.append("*END STEP")
    return lines


def parse_element_values(text):
    """Per element, the integration-point mean of stresses and strains (6 components each)."""
    sums, block = {}, None
    for line in text.splitlines():
        low = line.strip().lower()
        if low.startswith("stresses (elem"):
            block = 0
            continue
        if low.startswith("strains (elem"):
            block = 1
            continue
        fields = line.split()
        if block is None or not fields:
            continue
        try:
            values = [float(x) for x in fields]
        except ValueError:
            block = None
            continue
        e = int(values[0])
        entry = sums.setdefault(e, [[0.0] * 6, [0.0] * 6, [0, 0]])
        for k in range(6):
            entry[block][k] += values[2 + k]
        entry[2][block] += 1
    out = {}
    for e, (s, t, n) in sums.items():
        if n[0] == 0 or n[1] == 0:
            raise RuntimeError(f"ccx printed no stress or no strain for element {e}")
        out[e] = ([x / n[0] for x in s], [x / n[1] for x in t])
    return out


def ccx_component(values, i, j):
    """Tensor component (i, j) from ccx's order xx, yy, zz, xy, xz, yz (tensor shear)."""
    index = {(0, 0): 0, (1, 1): 1, (2, 2): 2, (0, 1): 3, (1, 0): 3, (0, 2): 4, (2, 0): 4, (1, 2): 5, (2, 1): 5}
    return values[index[(i, j)]]


def homogenise(args):
    mesh = fe.read_inp(args.mesh)
    given = {}
    if args.scene:
        given.update(scene_materials(args.scene))
    if args.materials:
        given.update(fe.read_materials(args.materials))
    for text in args.material or []:
        key, mat = fe.parse_material(text)
        given[key] = mat
    materials = fe.assign_materials(mesh, given)
    if not args.strain > 0:
        raise fe.InputProblem("--strain: must be > 0")
    refs, corner = periodic_setup(mesh)
    slaves = read_constraints(args.mesh)
    if not slaves:
        raise fe.InputProblem(f"{args.mesh}: no *EQUATION: not a periodic mesh written by cisamr mesh")
    ref_ids = set(refs.values())
    fixed = corner
    if fixed is None:  # a void covers the min corner: fix the first master instead
        used = sorted({n for s in mesh.elsets for e in s["elements"] for n in e[1:]})
        fixed = next(n for n in used if n not in slaves and n not in ref_ids)
    dim = mesh.dim
    plane = fe.PLANE_TYPES.get(mesh.element_type, "")
    thickness = args.thickness if dim == 2 else 1.0
    # The box: CORNER0 (or the mesh's min) to the REF nodes' corner (the max face coordinates).
    hi = list(mesh.nodes[refs[0]])
    lo = [min(p[d] for n, p in mesh.nodes.items() if n not in ref_ids) for d in range(dim)]
    box_volume = thickness
    for d in range(dim):
        box_volume *= hi[d] - lo[d]
    volume_of = {}
    volumes = []
    for s in mesh.elsets:
        v = 0.0
        for e in s["elements"]:
            volume_of[e[0]] = fe.measure(mesh, e, thickness)
            v += volume_of[e[0]]
        volumes.append(v)
    fractions = [v / box_volume for v in volumes]
    phase_c = [stiffness(dim, plane, m) for m in materials]
    n = len(voigt_pairs(dim))
    voigt = [[sum(f * c[i][j] for f, c in zip(fractions, phase_c)) for j in range(n)] for i in range(n)]
    solid = sum(fractions)
    if abs(solid - 1) < 1e-9:
        compliance = [[sum(f * s[i][j] for f, s in zip(fractions, map(inverse, phase_c))) for j in range(n)] for i in range(n)]
        reuss = inverse(compliance)
    else:
        reuss = [[0.0] * n for _ in range(n)]

    workdir = args.workdir or tempfile.mkdtemp(prefix="cisamr_homogenise_")
    os.makedirs(workdir, exist_ok=True)
    include_name = "mesh.inp"
    shutil.copyfile(args.mesh, os.path.join(workdir, include_name))
    model = fe.model_text(mesh, materials, thickness, include_name)
    columns, cases, seconds = [], [], 0.0
    try:
        for k, (p, q) in enumerate(voigt_pairs(dim)):
            eps = [[0.0] * dim for _ in range(dim)]
            # Engineering shear: gamma_pq = strain, tensor component strain / 2.
            value = args.strain if p == q else args.strain / 2
            eps[p][q] = eps[q][p] = value
            dat, t = fe.run_ccx(args.ccx, workdir, model + case_job(mesh, refs, fixed, eps, lo, hi))
            seconds += t
            elements = parse_element_values(dat)
            missing = [e for e in volume_of if e not in elements]
            if missing:
                raise RuntimeError(f"ccx printed nothing for element {missing[0]}")
            mean = [sum(volume_of[e] * ccx_component(elements[e][0], i, j) for e in volume_of) / box_volume
                    for i, j in voigt_pairs(dim)]
            deviation = max(abs(ccx_component(elements[e][1], i, j) - eps[i][j])
                            for e in volume_of for i in range(dim) for j in range(dim)) / args.strain
            columns.append([s / args.strain for s in mean])
            cases.append({"strain": [[x for x in row] for row in eps], "mean_stress": mean,
                          "max_strain_deviation": deviation})
    finally:
        if not args.workdir:
            shutil.rmtree(workdir, ignore_errors=True)
    c = [[columns[j][i] for j in range(n)] for i in range(n)]
    scale = max(abs(x) for row in c for x in row)
    asymmetry = max(abs(c[i][j] - c[j][i]) for i in range(n) for j in range(n)) / scale
    return {
        "mesh": args.mesh, "dimension": dim, "element_type": mesh.element_type, "plane": plane,
        "thickness": thickness if dim == 2 else None, "box": {"min": lo, "max": hi[:dim]},
        "fixed_node": fixed, "reference_nodes": {AXES[a]: r for a, r in refs.items()},
        "slaves": len(slaves), "elements": len(volume_of), "strain": args.strain,
        "voigt_order": ["".join(str(i + 1) + str(j + 1)) for i, j in voigt_pairs(dim)],
        "phases": [{"id": s["id"], "name": s["full_name"], "elset": s["name"], "E": m["E"], "nu": m["nu"],
                    "volume": v, "fraction": f}
                   for s, m, v, f in zip(mesh.elsets, materials, volumes, fractions)],
        "stiffness": c, "voigt": voigt, "reuss": reuss, "asymmetry": asymmetry,
        # Loewner order: the smallest eigenvalues of C - Reuss and Voigt - C (>= 0 up to rounding).
        "min_eig_above_reuss": symmetric_eigenvalues(
            [[(c[i][j] + c[j][i]) / 2 - reuss[i][j] for j in range(n)] for i in range(n)])[0],
        "min_eig_below_voigt": symmetric_eigenvalues(
            [[voigt[i][j] - (c[i][j] + c[j][i]) / 2 for j in range(n)] for i in range(n)])[0],
        "cases": cases, "max_strain_deviation": max(k["max_strain_deviation"] for k in cases),
        "ccx_seconds": seconds,
    }


def scene_materials(path):
    try:
        with open(path, encoding="utf-8") as f:
            scene = json.load(f)
    except (OSError, ValueError) as e:
        raise fe.InputProblem(f"{path}: cannot read the scene: {e}")
    out = {}
    for p in scene.get("phases", []):
        m = p.get("material", p)
        if isinstance(m, dict) and "E" in m and "nu" in m:
            out[str(p.get("name", p.get("id")))] = {"E": float(m["E"]), "nu": float(m["nu"])}
    return out


def print_result(r, out):
    kind = f"{r['dimension']}D {r['element_type']}" + (f" (plane {r['plane']})" if r["plane"] else "")
    print(f"{r['mesh']}: {kind}, {r['elements']} elements, {r['slaves']} slave nodes; "
          f"{len(r['cases'])} ccx runs, {r['ccx_seconds']:.2f} s", file=out)
    for p in r["phases"]:
        print(f"  phase {p['id']} {p['name']}: E {p['E']:g}, nu {p['nu']:g}, volume fraction {p['fraction']:.6f}", file=out)
    for name in ("stiffness", "voigt", "reuss"):
        print(f"{name} (Voigt order {' '.join(r['voigt_order'])}):", file=out)
        for row in r[name]:
            print("  " + " ".join(f"{x: .6e}" for x in row), file=out)
    print(f"asymmetry {r['asymmetry']:.2e}; smallest eigenvalue of C - Reuss {r['min_eig_above_reuss']:.4e}, "
          f"of Voigt - C {r['min_eig_below_voigt']:.4e}", file=out)
    print(f"largest element strain deviation from the imposed strain / strain: {r['max_strain_deviation']:.3e}",
          file=out)


def main(argv):
    parser = argparse.ArgumentParser(description="Periodic homogenisation of a cisamr .inp mesh with CalculiX")
    parser.add_argument("mesh", help="a periodic .inp written by cisamr mesh")
    parser.add_argument("--material", action="append", metavar="PHASE=E,NU",
                        help="material of a phase (name, ELSET name or id); repeat per phase")
    parser.add_argument("--materials", metavar="M.json", help='{"PHASE": {"E": ..., "nu": ...}, ...}')
    parser.add_argument("--scene", metavar="SCENE.json", help="materials from the scene's phases when they carry E, nu")
    parser.add_argument("--strain", type=float, default=1e-3, help="magnitude of each unit strain (default 1e-3)")
    parser.add_argument("--thickness", type=float, default=1.0, help="2D: section thickness (default 1)")
    parser.add_argument("--workdir", help="keep the CalculiX jobs and their output here")
    parser.add_argument("--json", metavar="OUT", help="write the results as JSON ('-': standard output)")
    parser.add_argument("--ccx", default="ccx", help="the CalculiX executable (default ccx)")
    return fe.run_tool("homogenise", parser.parse_args(argv), homogenise, print_result)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
