#!/bin/bash
# Cohesive meshes (issue #13) read back by readers that did not write them: meshio reads the
# .vtu (quads / wedges with cell data cohesive = 1) and the .msh (quadrangles / prisms in
# COH_<A>_<B> physical groups) of a 2D and a 3D scene, with the same number of cohesive
# cells in both; every top node lies on its bottom node bit for bit (file orders of
# mesh/cohesive.hpp); no node is used by bulk cells of two phases; gmsh re-reads the .msh
# and writes it again with the same cohesive cells. (`gmsh -check` is no test here: it
# reports the duplicated interface nodes, which is what a cohesive mesh is, as an error.)
# meshio also reads the .inp, once COH2D4 -> quad and COH3D6 -> wedge (and CPE3; none is in
# meshio 5's Abaqus element-type table) are added to that table: the same numbers of
# nodes, bulk cells and cohesive cells per phase pair as the .vtu, every cohesive cell in
# exactly one COH_<A>_<B> element set, every top node on its bottom node (COH3D6 node k+3 at
# node k; COH2D4 node 4 at node 1 and 3 at node 2), the bottom facet a face of a bulk cell
# of phase A and the top facet one of phase B (A's id below B's), and the bottom's
# right-hand normal ((2-1)x(3-1) in 3D, 1->2 turned by +90 degrees in 2D) pointing into the
# B cell and away from the A cell: what Abaqus's default STACK DIRECTION needs.
# usage: cohesive_readback.sh CISAMR SOURCE_DIR
set -u
cisamr=$1 source_dir=$2
. "$(dirname "$0")/common.sh"
check='
import sys, meshio, numpy as np
m = meshio.read(sys.argv[1])
p = m.points
pairs = {"quad": [(0, 3), (1, 2)], "wedge": [(0, 3), (1, 4), (2, 5)]}  # VTK and Gmsh orders alike
bulk = {"tetra"} if any(b.type == "tetra" for b in m.cells) else {"triangle"}  # 3D triangles are box faces
phase = m.cell_data.get("phase") or m.cell_data.get("gmsh:physical")
cohesive = bad = 0
owner = {}
mixed = 0
for block, ph in zip(m.cells, phase):
    if block.type in pairs:
        cohesive += len(block.data)
        for a, b in pairs[block.type]:
            bad += int((p[block.data[:, a]] != p[block.data[:, b]]).any(axis=1).sum())
    elif block.type in bulk:
        for cell, f in zip(block.data, ph):
            for n in cell:
                if owner.setdefault(int(n), int(f)) != int(f):
                    mixed += 1
print("%s: %d cohesive cells, %d tops off their bottoms, %d nodes shared by two phases" % (sys.argv[1].rsplit("/", 1)[-1], cohesive, bad, mixed))
open(sys.argv[2], "w").write(str(cohesive))
sys.exit(1 if bad or mixed or cohesive == 0 else 0)
'
inp_check='
import sys, meshio, numpy as np
import meshio.abaqus._abaqus as abaqus
for name, kind in {"COH2D4": "quad", "COH3D6": "wedge", "CPE3": "triangle", "CPS3": "triangle", "C3D4": "tetra"}.items():
    abaqus.abaqus_to_meshio_type.setdefault(name, kind)
inp, vtu = meshio.read(sys.argv[1]), meshio.read(sys.argv[2])
problems = []
def check(ok, what):
    if not ok:
        problems.append(what)
names = bytes(vtu.field_data["phase_names"]).decode().split("\0")
phase_id = dict(zip(names, (int(i) for i in vtu.field_data["phase_ids"])))
inv = {v: k for k, v in phase_id.items()}
p = inp.points
dim = 3 if any(b.type == "wedge" for b in inp.cells) else 2
bulk_type, coh_type = ("tetra", "wedge") if dim == 3 else ("triangle", "quad")
# the .vtu: points, bulk cells, cohesive cells per (phase, phase_top)
vtu_pairs = {}
for block, ph, top in zip(vtu.cells, vtu.cell_data["phase"], vtu.cell_data["phase_top"]):
    if block.type == coh_type:
        for a, b in zip(ph, top):
            vtu_pairs[(int(a), int(b))] = vtu_pairs.get((int(a), int(b)), 0) + 1
vtu_bulk = sum(len(b.data) for b in vtu.cells if b.type == bulk_type)
# the .inp: bulk cells with their phase (the ELSET named after it), cohesive blocks
bulk, bulk_phase, coh = [], [], []
for i, block in enumerate(inp.cells):
    if block.type == bulk_type:
        owner = [n for n, sets in inp.cell_sets.items() if n in phase_id and len(sets[i]) == len(block.data)]
        check(len(owner) == 1, "bulk block %d: %s phase element sets" % (i, owner))
        bulk.append(block.data)
        bulk_phase.append(np.full(len(block.data), phase_id[owner[0]] if owner else -1))
    elif block.type == coh_type:
        coh.append(i)
    else:
        check(False, "unexpected %s block" % block.type)
bulk, bulk_phase = np.concatenate(bulk), np.concatenate(bulk_phase)
check(len(p) == len(vtu.points), "%d nodes, the .vtu has %d" % (len(p), len(vtu.points)))
check(len(bulk) == vtu_bulk, "%d bulk cells, the .vtu has %d" % (len(bulk), vtu_bulk))
# every cohesive cell in exactly one COH_ set; the set names its phases
seen = {i: np.zeros(len(inp.cells[i].data), dtype=int) for i in coh}
set_of = {i: np.full(len(inp.cells[i].data), "", dtype=object) for i in coh}
for name, sets in inp.cell_sets.items():
    if name.startswith("COH_"):
        for i in coh:
            np.add.at(seen[i], sets[i], 1)
            set_of[i][sets[i]] = name
cohesive = sum(len(s) for s in seen.values())
check(cohesive > 0, "no cohesive cell")
check(cohesive == sum(vtu_pairs.values()), "%d cohesive cells, the .vtu has %d" % (cohesive, sum(vtu_pairs.values())))
check(all((s == 1).all() for s in seen.values()), "cohesive cells in no COH_ set or in several: %d" % sum(int((s != 1).sum()) for s in seen.values()))
# facets of the bulk cells, keyed by their sorted nodes (base n: exact below 2M nodes in 3D);
# apex = the cell vertex off the facet
n = np.int64(len(p))
def key(nodes):
    s = np.sort(nodes, axis=1).astype(np.int64)
    k = s[:, 0]
    for c in range(1, s.shape[1]):
        k = k * n + s[:, c]
    return k
facet_keys = np.concatenate([key(np.delete(bulk, j, axis=1)) for j in range(dim + 1)])
facet_cell = np.tile(np.arange(len(bulk)), dim + 1)
facet_apex = np.concatenate([bulk[:, j] for j in range(dim + 1)])
order = np.argsort(facet_keys, kind="stable")
facet_keys, facet_cell, facet_apex = facet_keys[order], facet_cell[order], facet_apex[order]
def find(nodes):  # the one bulk cell with this facet (-1: none or several) and its apex
    k = key(nodes)
    lo, hi = np.searchsorted(facet_keys, k, "left"), np.searchsorted(facet_keys, k, "right")
    one = hi - lo == 1
    at = np.where(one, lo, 0)
    return np.where(one, facet_cell[at], -1), facet_apex[at]
def orient(b, x):  # sign of the bottom right-hand normal . (x - b0)
    q = p[:, :dim]
    if dim == 3:
        normal = np.cross(q[b[:, 1]] - q[b[:, 0]], q[b[:, 2]] - q[b[:, 0]])
    else:
        e = q[b[:, 1]] - q[b[:, 0]]
        normal = np.stack([-e[:, 1], e[:, 0]], axis=1)
    return np.einsum("ij,ij->i", normal, q[x] - q[b[:, 0]])
off = wrong_side = wrong_phase = wrong_set = unmatched = 0
inp_pairs = {}
for i in coh:
    c = inp.cells[i].data
    # file order: 3D bottom 1-2-3, top 4-5-6 (k+3 over k); 2D bottom 1-2, top 3-4 (4 over 1, 3 over 2)
    b, t = (c[:, :3], c[:, 3:]) if dim == 3 else (c[:, :2], c[:, [3, 2]])
    off += int((p[b] != p[t]).any(axis=(1, 2)).sum())
    lower, lower_apex = find(b)
    upper, upper_apex = find(t)
    bad = (lower < 0) | (upper < 0)
    unmatched += int(bad.sum())
    ok = ~bad
    pl, pu = bulk_phase[lower[ok]], bulk_phase[upper[ok]]
    wrong_phase += int((pl >= pu).sum())
    wrong_side += int(((orient(b[ok], upper_apex[ok]) <= 0) | (orient(b[ok], lower_apex[ok]) >= 0)).sum())
    for a, u, s in zip(pl, pu, set_of[i][ok]):
        inp_pairs[(int(a), int(u))] = inp_pairs.get((int(a), int(u)), 0) + 1
        wrong_set += s != "COH_%s_%s" % (inv.get(int(a)), inv.get(int(u)))
check(inp_pairs == vtu_pairs, "cohesive cells per phase pair %s, the .vtu has %s" % (inp_pairs, vtu_pairs))
for count, what in ((off, "tops off their bottoms"), (unmatched, "bottom or top facets not the face of exactly one bulk cell"),
                    (wrong_phase, "bottoms not on the lower phase id"), (wrong_side, "bottom normals not pointing into the top cell"),
                    (wrong_set, "cells in the COH_ set of another phase pair")):
    check(count == 0, "%d %s" % (count, what))
print("%s: %d nodes, %d bulk cells, %d cohesive cells %s%s" % (sys.argv[1].rsplit("/", 1)[-1], len(p), len(bulk), cohesive,
      {"COH_%s_%s" % (inv[a], inv[b]): k for (a, b), k in sorted(inp_pairs.items())}, "".join("\n  " + x for x in problems)))
sys.exit(1 if problems else 0)
'
for scene in composite spheres3d; do
  "$cisamr" mesh "$source_dir/data/examples/$scene.json" -o "$dir/$scene.inp" --cohesive -q || fail "mesh $scene.inp"
  for ext in vtu msh; do
    "$cisamr" mesh "$source_dir/data/examples/$scene.json" -o "$dir/$scene.$ext" --cohesive -q || fail "mesh $scene.$ext"
    /usr/bin/python3 -c "$check" "$dir/$scene.$ext" "$dir/$scene.$ext.count" || fail "meshio: $scene.$ext"
  done
  cmp -s "$dir/$scene.vtu.count" "$dir/$scene.msh.count" || fail "$scene: the .vtu and the .msh hold different numbers of cohesive cells"
  grep -q '"COH_' "$dir/$scene.msh" || fail "$scene: no COH_ physical group"
  /usr/bin/python3 -c "$inp_check" "$dir/$scene.inp" "$dir/$scene.vtu" || fail "meshio: $scene.inp"
  gmsh "$dir/$scene.msh" -0 -format msh41 -o "$dir/$scene.g.msh" > "$dir/gmsh.log" 2>&1 || fail "gmsh cannot re-read $scene.msh: $(tail -3 "$dir/gmsh.log")"
  /usr/bin/python3 -c "$check" "$dir/$scene.g.msh" "$dir/$scene.g.count" || fail "meshio: gmsh's rewrite of $scene.msh"
  cmp -s "$dir/$scene.g.count" "$dir/$scene.msh.count" || fail "$scene: gmsh's rewrite lost cohesive cells"
done
echo "cohesive read-back: ok"
