#!/bin/bash
# Cohesive meshes (issue #13) read back by readers that did not write them: meshio reads the
# .vtu (quads / wedges with cell data cohesive = 1) and the .msh (quadrangles / prisms in
# COH_<A>_<B> physical groups) of a 2D and a 3D scene, with the same number of cohesive
# cells in both; every top node lies on its bottom node bit for bit (file orders of
# mesh/cohesive.hpp); no node is used by bulk cells of two phases; gmsh re-reads the .msh
# and writes it again with the same cohesive cells. (`gmsh -check` is no test here: it
# reports the duplicated interface nodes, which is what a cohesive mesh is, as an error.)
# usage: cohesive_readback.sh CISAMR SOURCE_DIR
set -u
cisamr=$1 source_dir=$2
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
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
for scene in composite spheres3d; do
  for ext in vtu msh; do
    "$cisamr" mesh "$source_dir/data/examples/$scene.json" -o "$dir/$scene.$ext" --cohesive -q || fail "mesh $scene.$ext"
    /usr/bin/python3 -c "$check" "$dir/$scene.$ext" "$dir/$scene.$ext.count" || fail "meshio: $scene.$ext"
  done
  cmp -s "$dir/$scene.vtu.count" "$dir/$scene.msh.count" || fail "$scene: the .vtu and the .msh hold different numbers of cohesive cells"
  grep -q '"COH_' "$dir/$scene.msh" || fail "$scene: no COH_ physical group"
  gmsh "$dir/$scene.msh" -0 -format msh41 -o "$dir/$scene.g.msh" > "$dir/gmsh.log" 2>&1 || fail "gmsh cannot re-read $scene.msh: $(tail -3 "$dir/gmsh.log")"
  /usr/bin/python3 -c "$check" "$dir/$scene.g.msh" "$dir/$scene.g.count" || fail "meshio: gmsh's rewrite of $scene.msh"
  cmp -s "$dir/$scene.g.count" "$dir/$scene.msh.count" || fail "$scene: gmsh's rewrite lost cohesive cells"
done
echo "cohesive read-back: ok"
