#!/bin/bash
# Boundary sets through the command line, read back by independent readers
# (boundary_sets_check.py: meshio for .inp/.msh/.mesh/.vtu, VTK for .vtu/.pvtu): 2D and 3D,
# sequential, --partitions N and under mpiexec (pieces and --gather); gmsh accepts the
# .msh with its face entities and physical groups; --plane picks CPE3/CPS3.
# usage: boundary_sets.sh CISAMR SOURCE_DIR [MPIEXEC]
set -u
cisamr=$1 source_dir=$2 mpiexec=${3:-}
check=$source_dir/tests/e2e/boundary_sets_check.py
. "$(dirname "$0")/common.sh"
run_mpi() { local n=$1; shift; timeout 60 "$mpiexec" -n "$n" --oversubscribe --allow-run-as-root "$@"; }
# Sorted "NAME size" lines of an .inp's node sets and element sets (meshio).
inp_sets() {
  /usr/bin/python3 -c 'import meshio, sys
m = meshio.read(sys.argv[1])
for k, v in sorted(m.point_sets.items()): print("NSET", k, len(v))
for k, v in sorted(m.cell_sets.items()): print("ELSET", k, sum(len(a) for a in v))' "$1"
}

# Decimal domains whose max faces the lattice places off the decimal value (-0.7 + 7·0.1),
# inclusions crossing faces, edges and corners.
cat > "$dir/s2.json" <<'JSON'
{"format": "cisamr-scene/1", "dimension": 2,
 "domain": {"min": [0.1, -0.7], "max": [1.3, 0.0]}, "mesh": {"h": 0.1, "levels": 1},
 "phases": [{"id": 1, "name": "matrix"}, {"id": 2, "name": "glass fibre"}, {"id": 5, "name": "rubber"}],
 "inclusions": [{"shape": "circle", "center": [0.5, -0.35], "radius": 0.17, "phase": 2},
                {"shape": "circle", "center": [1.3, 0.0], "radius": 0.12, "phase": 5},
                {"shape": "ellipse", "center": [0.9, -0.7], "semi_axes": [0.2, 0.08], "angle": 0.3, "phase": 2}]}
JSON
cat > "$dir/s3.json" <<'JSON'
{"format": "cisamr-scene/1", "dimension": 3,
 "domain": {"min": [0.3, -0.7, 0.1], "max": [0.9, 0.0, 0.6]}, "mesh": {"h": 0.1, "levels": 1},
 "phases": [{"id": 1, "name": "epoxy"}, {"id": 2, "name": "silica"}, {"id": 3, "name": "fibre"}],
 "inclusions": [{"shape": "sphere", "center": [0.6, -0.35, 0.35], "radius": 0.12, "phase": 2},
                {"shape": "sphere", "center": [0.3, -0.7, 0.1], "radius": 0.1, "phase": 2},
                {"shape": "cylinder", "start": [0.2, -0.1, 0.5], "end": [1.0, -0.1, 0.5], "radius": 0.06, "phase": 3}]}
JSON

for d in 2 3; do
  scene=$dir/s$d.json
  for ext in inp msh mesh vtu; do
    "$cisamr" mesh "$scene" -o "$dir/m$d.$ext" -q || fail "$d""D: mesh -o .$ext"
  done
  gmsh -check "$dir/m$d.msh" > "$dir/gmsh$d.log" 2>&1 || { tail -5 "$dir/gmsh$d.log"; fail "$d""D: gmsh -check"; }
  ! grep -q "Error" "$dir/gmsh$d.log" || { grep Error "$dir/gmsh$d.log" | head -3; fail "$d""D: gmsh reports an error"; }
  gmsh "$dir/m$d.msh" -0 -o "$dir/rt$d.msh" > /dev/null 2>&1 || fail "$d""D: gmsh cannot re-write the .msh"
  for f in XMIN XMAX YMIN YMAX; do grep -q "\"$f\"" "$dir/rt$d.msh" || fail "$d""D: gmsh dropped physical group $f"; done

  pieces=()
  "$cisamr" mesh "$scene" -o "$dir/p$d.pvtu" --partitions 5 -q || fail "$d""D: --partitions 5 .pvtu"
  pieces+=("$dir/p$d.pvtu")
  # Sets of a partitioned / gathered run equal the sequential run's, set for set.
  inp_sets "$dir/m$d.inp" > "$dir/sets_seq$d.txt" || fail "$d""D: meshio cannot read the .inp"
  "$cisamr" mesh "$scene" -o "$dir/part$d.inp" --partitions 4 -q || fail "$d""D: --partitions 4 .inp"
  inp_sets "$dir/part$d.inp" | cmp -s - "$dir/sets_seq$d.txt" || fail "$d""D: --partitions 4: other sets than sequential"
  if [ -n "$mpiexec" ]; then
    for ranks in 2 3 4; do
      run_mpi $ranks "$cisamr" mesh "$scene" -o "$dir/r$ranks-$d.pvtu" -q || fail "$d""D: $ranks ranks .pvtu"
      pieces+=("$dir/r$ranks-$d.pvtu")
    done
    run_mpi 3 "$cisamr" mesh "$scene" -o "$dir/g$d.inp" --gather -q || fail "$d""D: 3 ranks --gather .inp"
    inp_sets "$dir/g$d.inp" | cmp -s - "$dir/sets_seq$d.txt" || fail "$d""D: 3 ranks --gather: other sets than sequential"
  fi
  /usr/bin/python3 "$check" "$scene" "$dir/m$d" "${pieces[@]}" || fail "$d""D: the readers disagree"
done

# --plane: CPS3 by default, CPE3 with strain; 3D stays C3D4.
"$cisamr" mesh "$dir/s2.json" -o "$dir/strain.inp" --plane strain -q || fail "--plane strain"
grep -q "TYPE=CPE3" "$dir/strain.inp" && ! grep -q "TYPE=CPS3" "$dir/strain.inp" || fail "--plane strain did not write CPE3"
grep -q "TYPE=CPS3" "$dir/m2.inp" || fail "the default 2D element is not CPS3"
"$cisamr" mesh "$dir/s2.json" -o "$dir/x.inp" --plane bending -q 2> "$dir/err.txt"
[ $? -eq 2 ] || fail "--plane bending: not a usage error"
echo "boundary sets: ok"
