#!/bin/bash
# Periodic 2D and 3D meshes read back by readers that did not write them: meshio (.msh, .inp, .vtu)
# finds the nodes of each max face to be the min face's translated by the period, bit for
# bit, with no node off a face by rounding; gmsh -check accepts the .msh; a broken copy
# (one max-face node moved by one ulp) is caught, so the check can fail.
# The constraints (docs/periodic-design.md §5): gmsh re-reads the .msh and writes it again
# (gmsh f.msh -0 -o g.msh, MSH 4.1) with the same $Periodic links (entities, affine map, node
# pairs); meshio reads the .vtu's periodic_master, each master the exact translate of its
# node; with MPI, the .pvtu pieces of `mpiexec -n 3` carry the same masters (by global id)
# as the gathered .vtu, and the .inp written with --gather equals one process's with the
# same 3 partitions (global ids depend on the partitions, not on the ranks).
# usage: periodic_readback.sh CISAMR [MPIEXEC]
set -u
cisamr=$1 mpiexec=${2:-}
. "$(dirname "$0")/common.sh"
cat > "$dir/rve2.json" <<'JSON'
{"format": "cisamr-scene/1", "dimension": 2,
 "domain": {"min": [0, 0], "max": [10, 10], "periodic": true}, "mesh": {"h": 0.5, "levels": 2},
 "phases": [{"id": 1, "name": "matrix"}, {"id": 2, "name": "particle"}, {"id": 3, "name": "pore", "void": true}],
 "inclusions": [{"shape": "circle", "center": [0.3, 9.6], "radius": 2.2, "phase": 2},
                {"shape": "ellipse", "center": [5, 0.2], "semi_axes": [2, 1], "angle": 0.3, "phase": 2},
                {"shape": "circle", "center": [9.9, 5], "radius": 1.3, "phase": 3}]}
JSON
# 3D: a sphere across a corner, a fibre through two faces, a pore through a third.
cat > "$dir/rve3.json" <<'JSON'
{"format": "cisamr-scene/1", "dimension": 3,
 "domain": {"min": [0, 0, 0], "max": [10, 10, 10], "periodic": true}, "mesh": {"h": 1.25, "levels": 1},
 "phases": [{"id": 1, "name": "matrix"}, {"id": 2, "name": "particle"}, {"id": 3, "name": "fibre"},
            {"id": 4, "name": "pore", "void": true}],
 "inclusions": [{"shape": "sphere", "center": [9.3, 9.5, 0.6], "radius": 2.1, "phase": 2},
                {"shape": "cylinder", "start": [3, -3, 7], "end": [3, 13, 7], "radius": 0.9, "phase": 3},
                {"shape": "sphere", "center": [5.5, 5, 9.7], "radius": 1.4, "phase": 4}]}
JSON
for d in 2 3; do
for ext in msh inp vtu; do
  "$cisamr" mesh "$dir/rve$d.json" -o "$dir/rve$d.$ext" -q || fail "mesh .$ext"
done
check='
import sys, meshio, numpy as np
dim = int(sys.argv[2])
m = meshio.read(sys.argv[1])
p = m.points[:, :dim]
lo, hi = np.zeros(dim), np.full(dim, 10.0)
bad = 0
for a in range(dim):
    rest = [b for b in range(dim) if b != a]
    mins = p[p[:, a] == lo[a]]
    maxs = p[p[:, a] == hi[a]]
    # Void facing across the period removes nodes on one side only: compare the nodes that
    # have a partner on the face, then require most of them to match exactly.
    s_min = set(map(tuple, mins[:, rest].tolist()))
    s_max = set(map(tuple, maxs[:, rest].tolist()))
    common = s_min & s_max
    if len(common) < 0.8 * max(len(s_min), len(s_max)) or len(common) < 10:
        print("axis", a, "min", len(s_min), "max", len(s_max), "common", len(common)); bad += 1
    near = np.abs(p[:, a] - lo[a]) < 1e-9
    near |= np.abs(p[:, a] - hi[a]) < 1e-9
    off = near & (p[:, a] != lo[a]) & (p[:, a] != hi[a])
    if off.any():
        print("axis", a, off.sum(), "nodes off the face by rounding"); bad += 1
sys.exit(1 if bad else 0)
'
for ext in msh inp vtu; do
  /usr/bin/python3 -c "$check" "$dir/rve$d.$ext" "$d" || fail "meshio: ${d}D .$ext faces do not match"
done
gmsh "$dir/rve$d.msh" -check > "$dir/gmsh$d.log" 2>&1 || fail "gmsh -check rejects the .msh: $(tail -3 "$dir/gmsh$d.log")"
# The same check must fail on a copy whose max-face nodes are off the face by one ulp.
/usr/bin/python3 - "$dir/rve$d.vtu" "$dir/broken$d.vtu" <<'PY' || fail "could not write the broken copy"
import sys, meshio, numpy as np
m = meshio.read(sys.argv[1])
on = m.points[:, 0] == 10.0
m.points[on, 0] = np.nextafter(10.0, 0.0)
meshio.write(sys.argv[2], m)
PY
if /usr/bin/python3 -c "$check" "$dir/broken$d.vtu" "$d" > /dev/null; then fail "the check passes a broken mesh"; fi

# gmsh re-reads our $Periodic (a link whose entity it cannot find would desynchronise it)
# and writes the same links: node tags are kept, so the pairs compare by tag. (Debian's
# gmsh warns that it lacks ANN to match nodes itself; it keeps the pairs it read.)
gmsh "$dir/rve$d.msh" -0 -format msh41 -o "$dir/g$d.msh" > "$dir/gmsh0$d.log" 2>&1 || fail "gmsh cannot re-read the .msh: $(tail -3 "$dir/gmsh0$d.log")"
/usr/bin/python3 - "$dir/rve$d.msh" "$dir/g$d.msh" "$d" <<'PY' || fail "gmsh's \$Periodic differs from ours (${d}D)"
import sys
def periodic(path):
    lines = open(path).read().split("\n")
    if "$Periodic" not in lines:
        return None
    i = lines.index("$Periodic") + 1
    links = {}
    for _ in range(int(lines[i])):
        entities = tuple(map(int, lines[i + 1].split()))
        affine = [float(x) for x in lines[i + 2].split()]
        n = int(lines[i + 3])
        pairs = sorted(tuple(map(int, lines[i + 4 + k].split())) for k in range(n))
        links[entities] = (affine, pairs)
        i += 3 + n
    return links
ours, theirs = periodic(sys.argv[1]), periodic(sys.argv[2])
if not ours or len(ours) != int(sys.argv[3]):
    print("our .msh has no $Periodic link per axis:", ours and list(ours)); sys.exit(1)
if ours != theirs:
    print("ours", {k: (v[0], len(v[1])) for k, v in ours.items()}, "gmsh", theirs and {k: (v[0], len(v[1])) for k, v in theirs.items()}); sys.exit(1)
print("gmsh re-read: %d links, %d node pairs, identical" % (len(ours), sum(len(v[1]) for v in ours.values())))
PY

# meshio reads periodic_master: -1 off the max faces; elsewhere the global id of the node at
# the exact translate (max coordinates moved to the min face, the others bit-equal).
masters='
import sys, meshio, numpy as np
m = meshio.read(sys.argv[1])
dim = int(sys.argv[2])
pm, gid, p = m.point_data["periodic_master"], m.point_data["global_id"], m.points[:, :dim]
index = {g: i for i, g in enumerate(gid.tolist())}
lo, hi = 0.0, 10.0
bad = slaves = 0
for i in range(len(p)):
    on_max = p[i] == hi
    if not on_max.any():
        bad += pm[i] != -1; continue
    slaves += 1
    j = index.get(int(pm[i]))
    if j is None: bad += 1; continue
    want = np.where(on_max, lo, p[i])
    bad += not (p[j] == want).all()
print("meshio %s: %d slaves, %d wrong masters" % (sys.argv[1].rsplit("/", 1)[-1], slaves, bad))
sys.exit(1 if bad or slaves < 20 else 0)
'
/usr/bin/python3 -c "$masters" "$dir/rve$d.vtu" "$d" || fail "meshio: periodic_master of the .vtu"

if [ -n "$mpiexec" ]; then
  run_mpi() { local n=$1; shift; timeout 60 "$mpiexec" -n "$n" --oversubscribe --allow-run-as-root "$@"; }
  run_mpi 3 "$cisamr" mesh "$dir/rve$d.json" -o "$dir/par$d.pvtu" -q || fail "mpiexec -n 3: .pvtu"
  run_mpi 3 "$cisamr" mesh "$dir/rve$d.json" -o "$dir/whole$d.vtu" --gather -q || fail "mpiexec -n 3: --gather .vtu"
  # Global ids depend on the partitions, not on the ranks: 3 partitions on 3 ranks or on one
  # process give the same file, constraints included.
  run_mpi 3 "$cisamr" mesh "$dir/rve$d.json" -o "$dir/whole$d.inp" --gather -q || fail "mpiexec -n 3: --gather .inp"
  "$cisamr" mesh "$dir/rve$d.json" -o "$dir/one$d.inp" --partitions 3 -q || fail "--partitions 3: .inp"
  cmp -s "$dir/whole$d.inp" "$dir/one$d.inp" || fail "${d}D: the .inp of mpiexec -n 3 --gather differs from one process's with --partitions 3"
  grep -q 'Name="periodic_master"' "$dir/par$d.pvtu" || fail "the .pvtu does not declare periodic_master"
  /usr/bin/python3 -c "$masters" "$dir/whole$d.vtu" "$d" || fail "meshio: periodic_master of the gathered .vtu"
  # Each piece alone: node by node (global id), the master the gathered mesh gives.
  /usr/bin/python3 - "$dir/whole$d.vtu" "$dir"/par${d}_*.vtu <<'PY' || fail "the pieces' periodic_master differ from the gathered mesh's"
import sys, meshio
def masters(path):
    m = meshio.read(path)
    return dict(zip(m.point_data["global_id"].tolist(), m.point_data["periodic_master"].tolist()))
whole = masters(sys.argv[1])
bad = remote = slaves = 0
for piece in sys.argv[2:]:
    part = masters(piece)
    for g, q in part.items():
        bad += whole.get(g) != q
        slaves += q >= 0
        remote += q >= 0 and q not in part
print("%d pieces: %d slave copies, %d with the master on another rank, %d mismatches" % (len(sys.argv) - 2, slaves, remote, bad))
sys.exit(1 if bad or slaves == 0 else 0)
PY
fi
done
echo "periodic read-back: ok"
