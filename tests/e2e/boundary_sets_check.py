#!/usr/bin/python3
"""Reads the boundary sets of one mesh written in every format with independent readers
(meshio for .inp/.msh/.mesh/.vtu, VTK for .vtu/.pvtu) and checks that they agree.

    boundary_sets_check.py SCENE.json STEM [PVTU...]

STEM.inp, STEM.msh, STEM.mesh and STEM.vtu are the same mesh. Each PVTU (a parallel run's
pieces) must carry the same boundary bits per node position as STEM.vtu. Prints one line
per problem and exits 1 if there is any."""
import json
import sys

import meshio
import numpy
import vtk
from vtk.util.numpy_support import vtk_to_numpy

FACES = ["XMIN", "XMAX", "YMIN", "YMAX", "ZMIN", "ZMAX"]
problems = []


def check(ok, what):
    if not ok:
        problems.append(what)


def read_vtk(path):
    reader = vtk.vtkXMLPUnstructuredGridReader() if path.endswith(".pvtu") else vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(path)
    reader.Update()
    return reader.GetOutput()


def bits_by_position(grid, dim):
    points = vtk_to_numpy(grid.GetPoints().GetData())[:, :dim]
    bits = vtk_to_numpy(grid.GetPointData().GetArray("boundary"))
    return {tuple(p): int(b) for p, b in zip(points.tolist(), bits.tolist())}


scene_path, stem = sys.argv[1], sys.argv[2]
scene = json.load(open(scene_path))
dim = scene["dimension"]
faces = FACES[:2 * dim]

# VTU (VTK's reader): the bits, and the phase names as field data.
grid = read_vtk(stem + ".vtu")
points = vtk_to_numpy(grid.GetPoints().GetData())[:, :dim]
bits = vtk_to_numpy(grid.GetPointData().GetArray("boundary"))
node_counts = {f: int(((bits >> k) & 1).sum()) for k, f in enumerate(faces)}
check(all(node_counts[f] > 0 for f in faces), f"vtu: a face without nodes: {node_counts}")
names = grid.GetFieldData().GetAbstractArray("phase_names")
ids = grid.GetFieldData().GetArray("phase_ids")
check(names is not None and ids is not None, "vtu: no phase_names / phase_ids field data")
want_names = {p["id"]: p["name"] for p in scene["phases"]}


def names_by_id(name_bytes, phase_ids):
    """The names' bytes, each name ended by 0, paired with the ids in order."""
    split = bytes(int(b) for b in name_bytes).split(b"\0")[:-1]
    return {int(i): n.decode("utf-8") for i, n in zip(phase_ids, split)}


if names is not None and ids is not None:
    got = names_by_id(vtk_to_numpy(names), vtk_to_numpy(ids))
    check(got == want_names, f"vtu: phase names {got}, scene {want_names}")

# VTU (meshio): the same bits, phases and names.
vtu = meshio.read(stem + ".vtu")
check(numpy.array_equal(vtu.point_data["boundary"], bits), "meshio vtu: boundary bits differ from VTK's")
check(sum(len(c) for c in vtu.cell_data["phase"]) == grid.GetNumberOfCells(), "meshio vtu: phase count")
got = names_by_id(vtu.field_data["phase_names"], vtu.field_data["phase_ids"])
check(got == want_names, f"meshio vtu: phase names {got}, scene {want_names}")
lo, hi = points.min(axis=0), points.max(axis=0)
for k, f in enumerate(faces):
    axis, side = divmod(k, 2)
    on = ((bits >> k) & 1).astype(bool)
    plane = hi[axis] if side else lo[axis]
    check(numpy.all(points[on, axis] == plane), f"vtu: a node of {f} off the plane")
    check(numpy.all(points[~on, axis] != plane), f"vtu: a node on the {f} plane without its bit")

# INP (meshio): node sets equal the VTU bits; CORNER0 at the min corner; face ELSETs.
inp = meshio.read(stem + ".inp")
for k, f in enumerate(faces):
    check(f in inp.point_sets, f"inp: no NSET {f}")
    if f in inp.point_sets:
        check(len(inp.point_sets[f]) == node_counts[f], f"inp: NSET {f} has {len(inp.point_sets[f])} nodes, vtu {node_counts[f]}")
        # Both files number the nodes alike (.inp ids = .vtu index + 1).
        on_vtu = set(numpy.nonzero((bits >> k) & 1)[0].tolist())
        check(set(inp.point_sets[f].tolist()) == on_vtu, f"inp: NSET {f} holds other nodes than the vtu's bit {k}")
check("CORNER0" in inp.point_sets and len(inp.point_sets["CORNER0"]) == 1, "inp: no single-node CORNER0")
if "CORNER0" in inp.point_sets:
    check(numpy.array_equal(points[inp.point_sets["CORNER0"][0]], lo), "inp: CORNER0 is not the node at the min corner")
inp_faces = {f: sum(sum(len(a) for a in inp.cell_sets[s]) for s in inp.cell_sets if s.startswith(f + "_S"))
             for f in faces}

# MSH (meshio): one cell set per face, the same facet count as the inp's element faces.
msh = meshio.read(stem + ".msh")
facet_type = "line" if dim == 2 else "triangle"
for f in faces:
    check(f in msh.cell_sets, f"msh: no physical group {f}")
    if f in msh.cell_sets:
        count = sum(len(ids) for block, ids in zip(msh.cells, msh.cell_sets[f]) if block.type == facet_type)
        check(count == inp_faces[f], f"msh: {f} has {count} facets, inp {inp_faces[f]}")
        check(count > 0, f"msh: {f} is empty")

# Medit (meshio): boundary facets with reference face + 1, as many as the msh's.
medit = meshio.read(stem + ".mesh")
refs = numpy.concatenate([r for block, r in zip(medit.cells, medit.cell_data["medit:ref"]) if block.type == facet_type])
for k, f in enumerate(faces):
    check(int((refs == k + 1).sum()) == inp_faces[f], f"mesh: reference {k + 1} has {(refs == k + 1).sum()} facets, inp {inp_faces[f]}")
check(set(refs.tolist()) <= set(range(1, 2 * dim + 1)), f"mesh: boundary references {sorted(set(refs.tolist()))}")

# Parallel pieces: the same bits at the same positions.
sequential = bits_by_position(grid, dim)
for pvtu in sys.argv[3:]:
    pieces = bits_by_position(read_vtk(pvtu), dim)
    check(pieces == sequential, f"{pvtu}: boundary bits differ from the sequential run's "
                                f"({sum(1 for p in pieces if pieces[p] != sequential.get(p))} positions)")

for p in problems:
    print("FAIL:", p)
print(f"{stem}: {dim}D, face nodes {node_counts}, face facets {inp_faces}: {'ok' if not problems else 'FAILED'}")
sys.exit(1 if problems else 0)
