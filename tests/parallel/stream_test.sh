#!/bin/bash
# `cisamr mesh --stream` (issue #15): partitions meshed one after another and written as
# .vtu pieces of their own, or as one Gmsh .msh or Abaqus .inp joined from every
# partition's chunks. On a 2D and a 3D example: the streamed mesh is the sequential
# one (report checksum), on 1 rank and under mpiexec; VTK reads the pieces back and finds
# exactly the in-memory path's mesh for the same partitions (global id -> point, cells as
# global ids with their phase); certify checks the streamed .pvtu against the scene; a mesh
# beyond what memory holds is streamed unasked when pieces are the output; what --stream
# cannot do is refused with exit 2, one line and no file left (no spool either).
# usage: stream_test.sh CISAMR EXAMPLES_DIR [MPIEXEC]
set -u
cisamr=$1 examples=$2 mpiexec=${3:-}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
run_mpi() { local n=$1; shift; timeout 60 "$mpiexec" -n "$n" --oversubscribe --allow-run-as-root "$@"; }
checksum() { sed -n 's/.*"checksum": "\([0-9a-f]*\)".*/\1/p' "$1"; }

# The same .msh content through meshio: cells and boundary facets as sets of coordinates
# with their physical tag, and the physical names (node numbering may differ).
same_msh() {  # same_msh A.msh B.msh
  /usr/bin/python3 - "$1" "$2" <<'EOF'
import sys
import meshio
import numpy as np
def load(path):
    m = meshio.read(path)
    cells = {}
    for block, tags in zip(m.cells, m.cell_data["gmsh:physical"]):
        keys = [tuple(sorted(map(tuple, c))) for c in m.points[block.data]]
        cells.setdefault(block.type, []).extend(zip(keys, tags.tolist()))
    names = {k: v.tolist() for k, v in m.field_data.items()}
    return len(m.points), {k: sorted(v) for k, v in cells.items()}, names
a, b = load(sys.argv[1]), load(sys.argv[2])
if a != b:
    print("differ:", a[0], b[0], {k: len(v) for k, v in a[1].items()}, {k: len(v) for k, v in b[1].items()}, a[2], b[2])
    sys.exit(1)
print(f"same .msh: {a[0]} nodes, " + ", ".join(f"{len(v)} {k}" for k, v in a[1].items()))
EOF
}

# The same .inp content through meshio: cells, element sets (phases, face sides) as sets of
# cells, node sets as sets of points (node numbering may differ).
same_inp() {  # same_inp A.inp B.inp
  /usr/bin/python3 - "$1" "$2" <<'EOF'
import sys
import meshio
def load(path):
    m = meshio.read(path)
    cells = {}
    for block in m.cells:
        cells.setdefault(block.type, []).extend(tuple(sorted(map(tuple, c))) for c in m.points[block.data])
    # element sets as sets of cells (coordinates), node sets as sets of points
    flat = [tuple(sorted(map(tuple, c))) for block in m.cells for c in m.points[block.data]]
    offsets, at = [], 0
    for block in m.cells:
        offsets.append(at); at += len(block.data)
    csets = {}
    for name, per_block in m.cell_sets.items():
        members = set()
        for b, idx in enumerate(per_block):
            if idx is None: continue
            for i in idx: members.add(flat[offsets[b] + int(i)])
        csets[name] = members
    psets = {name: set(map(tuple, m.points[idx])) for name, idx in m.point_sets.items()}
    return len(m.points), {k: sorted(v) for k, v in cells.items()}, csets, psets
a, b = load(sys.argv[1]), load(sys.argv[2])
if a != b:
    print("differ:", a[0], b[0], {k: len(v) for k, v in a[1].items()}, {k: len(v) for k, v in b[1].items()},
          sorted((k, len(v)) for k, v in a[2].items()), sorted((k, len(v)) for k, v in b[2].items()),
          sorted((k, len(v)) for k, v in a[3].items()), sorted((k, len(v)) for k, v in b[3].items()))
    sys.exit(1)
print(f"same .inp: {a[0]} nodes, " + ", ".join(f"{len(v)} {k}" for k, v in a[1].items()) +
      f", element sets {sorted(a[2])}, node sets {sorted(a[3])}")
EOF
}

# Two certificates (JSON) with the same verdicts and counts: the notes, the examples (which
# name pieces or not) and the sums' last digits (order of summation) aside.
same_certificate() {
  python3 - "$1" "$2" <<'EOF'
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
def strip(x, key=""):
    if isinstance(x, dict):
        return {k: strip(v, k) for k, v in x.items() if k not in ("notes", "examples", "mesh")}
    if isinstance(x, list):
        return [strip(v) for v in x]
    if isinstance(x, float):
        return round(x, 9 if key in ("measure", "mean", "measure_error", "relative_error") else 15)
    return x
if strip(a) != strip(b):
    print(json.dumps(strip(a))[:2000]); print(json.dumps(strip(b))[:2000])
    sys.exit(1)
EOF
}

# The same mesh through VTK's own .pvtu reader: points by global id, cells as sorted
# global-id tuples with their phase.
same_mesh() {  # same_mesh A.pvtu B.pvtu
  /usr/bin/python3 - "$1" "$2" <<'EOF'
import sys
import vtk
from vtk.util.numpy_support import vtk_to_numpy

def load(path):
    r = vtk.vtkXMLPUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    g = r.GetOutput()
    gid = vtk_to_numpy(g.GetPointData().GetArray("global_id"))
    xyz = vtk_to_numpy(g.GetPoints().GetData())
    points = {}
    for i, n in enumerate(gid):
        p = tuple(xyz[i])
        if points.setdefault(int(n), p) != p:
            sys.exit(f"{path}: global id {n} at two places")
    phase = vtk_to_numpy(g.GetCellData().GetArray("phase"))
    conn = vtk_to_numpy(g.GetCells().GetConnectivityArray())
    offs = vtk_to_numpy(g.GetCells().GetOffsetsArray())
    ratio = vtk_to_numpy(g.GetCellData().GetArray("aspect_ratio"))
    keyed = [(tuple(sorted(int(gid[k]) for k in conn[offs[c]:offs[c + 1]])), int(phase[c]), float(ratio[c]))
             for c in range(g.GetNumberOfCells())]
    cells = sorted(k[:2] for k in keyed)
    return points, cells, r.GetNumberOfPieces(), {k[0]: k[2] for k in keyed}

a, b = load(sys.argv[1]), load(sys.argv[2])
if a[0] != b[0]:
    sys.exit(f"points differ: {len(a[0])} vs {len(b[0])} global ids")
if a[1] != b[1]:
    sys.exit(f"cells differ: {len(a[1])} vs {len(b[1])}")
# The aspect_ratio arrays: a streamed piece takes the ratios its figures computed, an
# in-memory one computes them while writing; both are the metric's (vertex order may differ).
bad = [c for c, r in a[3].items() if abs(r - b[3][c]) > 1e-12 * r]
if bad:
    sys.exit(f"aspect_ratio differs on {len(bad)} cells, e.g. {bad[0]}: {a[3][bad[0]]} vs {b[3][bad[0]]}")
if sorted(a[0]) != list(range(len(a[0]))):
    sys.exit("global ids are not 0 .. n-1")
print(f"same mesh: {len(a[0])} nodes, {len(a[1])} cells, {a[2]} and {b[2]} pieces")
EOF
}

for scene in "$examples/composite.json" "$examples/spheres3d.json"; do
  name=$(basename "$scene" .json)
  "$cisamr" mesh "$scene" -o "$dir/$name-seq.vtu" --report "$dir/$name-seq.json" -q || fail "$name: sequential run"
  ref=$(checksum "$dir/$name-seq.json")
  [ -n "$ref" ] || fail "$name: no checksum"

  "$cisamr" mesh "$scene" -o "$dir/$name-s.pvtu" --stream --partitions 7 --report "$dir/$name-s.json" -q ||
    fail "$name: --stream, 7 partitions"
  [ "$(checksum "$dir/$name-s.json")" = "$ref" ] || fail "$name: --stream checksum differs from the sequential one"
  [ "$(ls "$dir" | grep -c "^$name-s_[0-6]\.vtu$")" = 7 ] || fail "$name: not one piece per partition"
  ls -a "$dir" | grep -q 'spool\|\.tmp\.' && fail "$name: a spool or a piece's temporary was left behind"

  "$cisamr" mesh "$scene" -o "$dir/$name-m.pvtu" --partitions 7 -q || fail "$name: in memory, 7 partitions"
  same_mesh "$dir/$name-s.pvtu" "$dir/$name-m.pvtu" || fail "$name: streamed and in-memory meshes differ"

  # Conformity across the pieces (by global id) and the bound; against the scene, the same
  # certificate as the sequential mesh's, line for line (the examples' collapsed nodes
  # included; the measure's last digits depend on the order of summation).
  "$cisamr" certify "$dir/$name-s.pvtu" -q || fail "$name: the streamed mesh does not certify"
  certificate() {
    "$cisamr" certify "$@" --scene "$scene" 2>&1 | tail -n +2 | sed -E 's/ \(relative error [^)]*\)//' |
      grep -v "^note: read piece by piece"
  }
  certificate "$dir/$name-s.pvtu" > "$dir/cert-s.txt"
  certificate "$dir/$name-seq.vtu" > "$dir/cert-seq.txt"
  diff "$dir/cert-s.txt" "$dir/cert-seq.txt" || fail "$name: the certificates differ"
  # Piece by piece (the default for a .pvtu) and merged (--whole): the same certificate, count
  # for count, with and without the scene.
  for with_scene in "--scene $scene" ""; do
    # shellcheck disable=SC2086
    "$cisamr" certify "$dir/$name-s.pvtu" $with_scene --json "$dir/pieces.json" -q
    grep -q '"read piece by piece' "$dir/pieces.json" || fail "$name: the .pvtu was not read piece by piece"
    # shellcheck disable=SC2086
    "$cisamr" certify "$dir/$name-s.pvtu" $with_scene --whole --json "$dir/whole.json" -q
    same_certificate "$dir/pieces.json" "$dir/whole.json" || fail "$name: piece by piece and --whole differ ($with_scene)"
    # shellcheck disable=SC2086
    "$cisamr" certify "$dir/$name-s.pvtu" $with_scene --threads 3 --json "$dir/threads.json" -q
    "$cisamr" certify "$dir/$name-s.pvtu" $with_scene --threads 1 --json "$dir/pieces.json" -q
    cmp -s "$dir/threads.json" "$dir/pieces.json" || fail "$name: --threads 3 and 1 give different certificates"
  done

  # One Gmsh file from the partitions' chunks: the sequential run's .msh (cells with their
  # physical groups, boundary facets per face, group names) through meshio, gmsh reads it
  # without error, certify gives the sequential certificate; no spool or chunk left.
  "$cisamr" mesh "$scene" -o "$dir/$name-seq.msh" -q || fail "$name: sequential .msh"
  "$cisamr" mesh "$scene" -o "$dir/$name-s.msh" --stream --partitions 7 --report "$dir/$name-sm.json" -q ||
    fail "$name: --stream .msh"
  [ "$(checksum "$dir/$name-sm.json")" = "$ref" ] || fail "$name: --stream .msh checksum differs"
  ls -a "$dir" | grep -q "spool\|chunk" && fail "$name: a spool or chunk was left behind"
  same_msh "$dir/$name-s.msh" "$dir/$name-seq.msh" || fail "$name: the streamed .msh is not the sequential one"
  gmsh -check "$dir/$name-s.msh" > "$dir/gmsh.log" 2>&1 && ! grep -q Error "$dir/gmsh.log" ||
    fail "$name: gmsh -check: $(grep Error "$dir/gmsh.log" | head -2)"
  certificate "$dir/$name-s.msh" > "$dir/cert-sm.txt"
  diff "$dir/cert-sm.txt" "$dir/cert-seq.txt" || fail "$name: the streamed .msh certificate differs"

  # One Abaqus file the same way: the sequential .inp's keyword lines, in order, and its
  # cells and sets through meshio; CalculiX finds the same apparent modulus on both.
  "$cisamr" mesh "$scene" -o "$dir/$name-seq.inp" -q || fail "$name: sequential .inp"
  "$cisamr" mesh "$scene" -o "$dir/$name-s.inp" --stream --partitions 7 --report "$dir/$name-si.json" -q ||
    fail "$name: --stream .inp"
  [ "$(checksum "$dir/$name-si.json")" = "$ref" ] || fail "$name: --stream .inp checksum differs"
  ls -a "$dir" | grep -q "spool\|chunk" && fail "$name: a spool or chunk was left behind (.inp)"
  diff <(grep '^\*' "$dir/$name-seq.inp" | grep -v '^\*\*') <(grep '^\*' "$dir/$name-s.inp" | grep -v '^\*\*') ||
    fail "$name: the streamed .inp's keyword lines differ"
  same_inp "$dir/$name-s.inp" "$dir/$name-seq.inp" || fail "$name: the streamed .inp is not the sequential one"
  if command -v ccx > /dev/null; then
    materials=()
    for set in $(sed -n 's/^\*ELEMENT.*ELSET=\(.*\)$/\1/p' "$dir/$name-seq.inp"); do
      materials+=(--material "$set=$((1000 * (${#materials[@]} + 1))),0.3")
    done
    for m in seq s; do
      /usr/bin/python3 "$examples/../../validation/fe/cisamr_fe.py" uniaxial "$dir/$name-$m.inp" "${materials[@]}" \
        --json "$dir/fe-$m.json" > /dev/null || fail "$name: CalculiX on the $m .inp"
    done
    /usr/bin/python3 -c 'import json, sys
a, b = (json.load(open(p))["apparent_modulus"] for p in sys.argv[1:3])
print(f"CalculiX: apparent modulus {a:.12g} (streamed) and {b:.12g} (sequential)")
sys.exit(0 if abs(a - b) <= 1e-9 * abs(b) else 1)' "$dir/fe-s.json" "$dir/fe-seq.json" || fail "$name: CalculiX moduli differ"
  fi

  if [ -n "$mpiexec" ]; then
    run_mpi 3 "$cisamr" mesh "$scene" -o "$dir/$name-3.inp" --stream --partitions 7 --report "$dir/$name-3i.json" -q ||
      fail "$name: 3 ranks --stream .inp"
    [ "$(checksum "$dir/$name-3i.json")" = "$ref" ] || fail "$name: 3 ranks --stream .inp checksum differs"
    same_inp "$dir/$name-3.inp" "$dir/$name-seq.inp" || fail "$name: 3 ranks stream another .inp"
    run_mpi 3 "$cisamr" mesh "$scene" -o "$dir/$name-3.msh" --stream --partitions 7 --report "$dir/$name-3m.json" -q ||
      fail "$name: 3 ranks --stream .msh"
    [ "$(checksum "$dir/$name-3m.json")" = "$ref" ] || fail "$name: 3 ranks --stream .msh checksum differs"
    same_msh "$dir/$name-3.msh" "$dir/$name-seq.msh" || fail "$name: 3 ranks stream another .msh"
    ls -a "$dir" | grep -q "spool\|chunk" && fail "$name: a spool or chunk was left behind (3 ranks)"
    run_mpi 3 "$cisamr" mesh "$scene" -o "$dir/$name-3.pvtu" --stream --partitions 7 --report "$dir/$name-3.json" -q ||
      fail "$name: 3 ranks --stream"
    [ "$(checksum "$dir/$name-3.json")" = "$ref" ] || fail "$name: 3 ranks --stream checksum differs"
    same_mesh "$dir/$name-3.pvtu" "$dir/$name-s.pvtu" || fail "$name: 3 ranks and 1 rank stream different meshes"
    run_mpi 2 "$cisamr" mesh "$scene" -o "$dir/$name-2.pvtu" --stream --report "$dir/$name-2.json" -q ||
      fail "$name: 2 ranks --stream, default partitions"
    [ "$(checksum "$dir/$name-2.json")" = "$ref" ] || fail "$name: 2 ranks --stream checksum differs"
    [ "$(ls "$dir" | grep -c "^$name-2_[0-9]*\.vtu$")" = 16 ] || fail "$name: default is not 8 partitions per rank"
  fi
done

# A piece that puts a node (by global id) elsewhere than another piece does: certify stops
# with exit 2 and one line naming that piece and global_id (nothing to certify: the pieces
# do not describe one mesh).
mkdir "$dir/moved" && cp "$dir"/composite-s.pvtu "$dir"/composite-s_*.vtu "$dir/moved/"
/usr/bin/python3 - "$dir/moved/composite-s_0.vtu" "$dir/moved/composite-s_1.vtu" <<'EOF' || fail "could not build the bad piece"
import sys
import vtk
from vtk.util.numpy_support import vtk_to_numpy
def read(path):
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    return r.GetOutput()
first, second = read(sys.argv[1]), read(sys.argv[2])
ids0 = set(vtk_to_numpy(first.GetPointData().GetArray("global_id")).tolist())
ids1 = vtk_to_numpy(second.GetPointData().GetArray("global_id"))
shared = [i for i, g in enumerate(ids1.tolist()) if g in ids0]
assert shared, "pieces 0 and 1 share no node"
p = list(second.GetPoint(shared[0]))
second.GetPoints().SetPoint(shared[0], p[0] + 1e-3, p[1], p[2])
w = vtk.vtkXMLUnstructuredGridWriter()
w.SetFileName(sys.argv[2])
w.SetInputData(second)
w.Write()
EOF
"$cisamr" certify "$dir/moved/composite-s.pvtu" > /dev/null 2> "$dir/moved.err"
[ $? = 2 ] || fail "a piece moving a shared node: not exit 2"
[ "$(wc -l < "$dir/moved.err")" = 1 ] && grep -q "composite-s_1.vtu.*global_id" "$dir/moved.err" ||
  fail "a piece moving a shared node: $(cat "$dir/moved.err")"

# Chosen automatically: pieces asked for, an estimate beyond what memory holds (here
# --max-elements) streams instead of refusing, with a note; the same mesh.
"$cisamr" mesh "$examples/composite.json" -o "$dir/auto.pvtu" --partitions 2 --max-elements 20000 \
  --report "$dir/auto.json" > /dev/null 2> "$dir/auto.err" || fail "automatic stream: $(cat "$dir/auto.err")"
grep -q "streamed over [0-9]* partitions" "$dir/auto.err" || fail "automatic stream: no note ($(cat "$dir/auto.err"))"
[ "$(checksum "$dir/auto.json")" = "$(checksum "$dir/composite-seq.json")" ] || fail "automatic stream: checksum differs"
# 8 partitions, whose share (0.15 of the 7.1e4 estimated elements at once) fits in 2e4.
grep -q "streamed over 8 partitions" "$dir/auto.err" || fail "automatic stream: not 8 partitions ($(cat "$dir/auto.err"))"
[ "$(ls "$dir" | grep -c '^auto_[0-9]*\.vtu$')" = 8 ] || fail "automatic stream: not one piece per partition"
# --stream without --partitions: more than 8 when 8 would not fit (1e4: 9 partitions hold
# 0.14 of the mesh at once, 8 hold 0.15, above).
"$cisamr" mesh "$examples/composite.json" -o "$dir/fewest.pvtu" --stream --max-elements 10000 -q ||
  fail "--stream, default partitions under --max-elements"
[ "$(ls "$dir" | grep -c '^fewest_[0-9]*\.vtu$')" = 9 ] || fail "--stream under --max-elements: not 9 partitions"
if [ -n "$mpiexec" ]; then  # one .msh of a parallel run (--gather) beyond memory: streamed as well
  run_mpi 2 "$cisamr" mesh "$examples/composite.json" -o "$dir/auto.msh" --gather --max-elements 20000 \
    --report "$dir/auto-msh.json" > /dev/null 2> "$dir/auto-msh.err" || fail "automatic .msh stream: $(cat "$dir/auto-msh.err")"
  grep -q "streamed over [0-9]* partitions" "$dir/auto-msh.err" || fail "automatic .msh stream: no note"
  [ "$(checksum "$dir/auto-msh.json")" = "$(checksum "$dir/composite-seq.json")" ] || fail "automatic .msh stream: checksum"
  same_msh "$dir/auto.msh" "$dir/composite-seq.msh" || fail "automatic .msh stream: not the sequential .msh"
fi

# Refused before any work: exit 2, one line naming the option or field, nothing written.
refused() {  # refused WHAT ARGS...
  local what=$1
  shift
  local out
  out=$("$cisamr" mesh "$@" --report "$dir/bad/report.json" 2>&1 >/dev/null)
  local code=$?
  [ "$code" = 2 ] || fail "$what: exit $code, expected 2 ($out)"
  [ "$(printf '%s\n' "$out" | wc -l)" = 1 ] || fail "$what: more than one line: $out"
  [ -z "$(ls -A "$dir/bad")" ] || fail "$what: left $(ls -A "$dir/bad")"
  echo "refused ($what): $out"
}
mkdir -p "$dir/bad"
refused "--gather" "$examples/composite.json" -o "$dir/bad/x.pvtu" --stream --gather
refused "not .pvtu, .msh or .inp" "$examples/composite.json" -o "$dir/bad/x.mesh" --stream
refused "--svg" "$examples/composite.json" -o "$dir/bad/x.pvtu" --stream --svg "$dir/bad/x.svg"
refused "--cohesive" "$examples/composite.json" -o "$dir/bad/x.pvtu" --stream --cohesive
refused "periodic" "$examples/rve3d.json" -o "$dir/bad/x.pvtu" --stream
refused "beyond --max-elements, one file" "$examples/composite.json" -o "$dir/bad/x.vtu" --max-elements 20000
# Two partitions hold 0.62 of the 7.1e4 estimated elements at once: above 2e4.
refused "too few partitions for --max-elements" "$examples/composite.json" -o "$dir/bad/x.pvtu" --stream --partitions 2 \
  --max-elements 20000
# A failure after meshing, while the pieces are written (piece 3's path is a directory):
# exit 2 naming it, and no piece, .pvtu, spool or report left, on 1 rank and on 3 (the
# piece then belongs to rank 1).
failed_write() {  # failed_write LAUNCHER...
  rm -rf "$dir/mid" && mkdir -p "$dir/mid/x_3.vtu"
  local out
  out=$("$@" "$cisamr" mesh "$examples/composite.json" -o "$dir/mid/x.pvtu" --stream --partitions 7 \
        --report "$dir/mid/r.json" 2>&1 >/dev/null)
  local code=$?
  [ "$code" = 2 ] || fail "a piece that cannot be written: exit $code ($out)"
  printf '%s\n' "$out" | grep -q "x_3.vtu" || fail "a piece that cannot be written: not named ($out)"
  [ "$(ls -A "$dir/mid")" = "x_3.vtu" ] || fail "a piece that cannot be written: left $(ls -A "$dir/mid")"
}
failed_write env
[ -n "$mpiexec" ] && failed_write run_mpi 3
echo "stream_test: ok"
