#!/bin/bash
# `cisamr mesh` on a 3D scene with STL surfaces, under mpiexec: the sequential mesher and
# the parallel one give the same checksum (1 rank and 7 partitions, 2 ranks and 5), a
# gathered .msh is byte-equal between 3 ranks and 1, and an STL file that one rank reads
# (its share) or cannot open ends every rank with one message and exit status 2 within
# seconds, leaving no output. The same with --cohesive (a gathered .inp).
# usage: cli_test3.sh CISAMR MPIEXEC SHAPES_DIR
set -u
cisamr=$1 mpiexec=$2 shapes=$3
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
run_mpi() { local n=$1; shift; timeout 30 "$mpiexec" -n "$n" --oversubscribe --allow-run-as-root "$@"; }
checksum() { sed -n 's/.*"checksum": "\([0-9a-f]*\)".*/\1/p' "$1"; }

# Tangent spheres of two phases, an STL octahedron overlapping a sphere of its phase (a
# union), an STL cube and a torus, spheres clipped by the domain; levels 0 and 1.
scene() {  # scene FILE TORUS_FILE
  cat > "$1" <<EOF
{"format": "cisamr-scene/1", "dimension": 3, "domain": {"min": [0, 0, 0], "max": [1.5, 1.5, 1.0]},
 "mesh": {"h": 0.125, "levels": 0},
 "phases": [{"id": 1, "name": "matrix"}, {"id": 2, "name": "particle"}, {"id": 3, "name": "fibre"}],
 "inclusions": [
  {"shape": "sphere", "center": [0.3125, 0.3125, 0.375], "radius": 0.1875, "phase": 2},
  {"shape": "sphere", "center": [0.625, 0.3125, 0.375], "radius": 0.125, "phase": 3},
  {"shape": "stl", "file": "$shapes/octahedron.stl", "scale": 0.2, "translate": [0.45, 1.05, 0.5], "phase": 2, "levels": 1},
  {"shape": "sphere", "center": [0.6, 1.1, 0.55], "radius": 0.1, "phase": 2, "levels": 1},
  {"shape": "stl", "file": "$shapes/cube.stl", "scale": 0.22, "translate": [1.05, 1.0, 0.35], "phase": 2},
  {"shape": "stl", "file": "$2", "scale": 0.12, "translate": [0.95, 0.9, 0.78], "phase": 3, "levels": 1},
  {"shape": "sphere", "center": [0.02, 0.8, 0.45], "radius": 0.14, "phase": 3},
  {"shape": "sphere", "center": [1.47, 1.46, 0.97], "radius": 0.2, "phase": 2}]}
EOF
}
scene "$dir/scene.json" "$shapes/torus.stl"

"$cisamr" mesh "$dir/scene.json" -o "$dir/seq.vtu" --extra-levels 1 --report "$dir/seq.json" -q || fail "sequential run"
ref=$(checksum "$dir/seq.json")
[ -n "$ref" ] || fail "no checksum in the sequential report"

"$cisamr" mesh "$dir/scene.json" -o "$dir/one.vtu" --extra-levels 1 --partitions 7 --report "$dir/one.json" -q ||
  fail "1 rank, 7 partitions"
[ "$(checksum "$dir/one.json")" = "$ref" ] || fail "1 rank, 7 partitions: checksum differs"

run_mpi 2 "$cisamr" mesh "$dir/scene.json" -o "$dir/two.pvtu" --extra-levels 1 --partitions 5 --report "$dir/two.json" -q ||
  fail "2 ranks"
[ "$(checksum "$dir/two.json")" = "$ref" ] || fail "2 ranks, 5 partitions: checksum differs"
grep -q '"stl_files_read"' "$dir/two.json" || fail "no STL file counts in the report"

run_mpi 3 "$cisamr" mesh "$dir/scene.json" -o "$dir/three.msh" --extra-levels 1 --partitions 8 --gather -q ||
  fail "3 ranks, --gather"
"$cisamr" mesh "$dir/scene.json" -o "$dir/single.msh" --extra-levels 1 --partitions 8 -q || fail "1 rank, 8 partitions"
cmp -s "$dir/three.msh" "$dir/single.msh" || fail "gathered .msh differs between 3 ranks and 1 rank"

# --cohesive (issue 13): the same checksum (bulk and cohesive cells) sequentially, on 1 rank
# with 7 partitions and on 2 ranks with 5; a gathered .inp byte-equal between 3 ranks and 1.
"$cisamr" mesh "$dir/scene.json" -o "$dir/cseq.inp" --extra-levels 1 --cohesive --report "$dir/cseq.json" -q ||
  fail "sequential --cohesive"
cref=$(checksum "$dir/cseq.json")
[ "$cref" != "$ref" ] || fail "--cohesive: the checksum does not count the cohesive cells"
grep -q '"COH_matrix_particle"' "$dir/cseq.json" || fail "--cohesive: no set in the report"
"$cisamr" mesh "$dir/scene.json" -o "$dir/cone.vtu" --extra-levels 1 --cohesive --partitions 7 --report "$dir/cone.json" -q ||
  fail "--cohesive, 1 rank, 7 partitions"
[ "$(checksum "$dir/cone.json")" = "$cref" ] || fail "--cohesive, 1 rank, 7 partitions: checksum differs"
run_mpi 2 "$cisamr" mesh "$dir/scene.json" -o "$dir/ctwo.pvtu" --extra-levels 1 --cohesive --partitions 5 --report "$dir/ctwo.json" -q ||
  fail "--cohesive, 2 ranks"
[ "$(checksum "$dir/ctwo.json")" = "$cref" ] || fail "--cohesive, 2 ranks, 5 partitions: checksum differs"
"$cisamr" certify "$dir/ctwo.pvtu" -q > /dev/null || fail "--cohesive, 2 ranks: the pieces do not certify"
run_mpi 3 "$cisamr" mesh "$dir/scene.json" -o "$dir/cthree.inp" --extra-levels 1 --cohesive --partitions 8 --gather -q ||
  fail "--cohesive, 3 ranks, --gather"
"$cisamr" mesh "$dir/scene.json" -o "$dir/csingle.inp" --extra-levels 1 --cohesive --partitions 8 -q ||
  fail "--cohesive, 1 rank, 8 partitions"
cmp -s "$dir/cthree.inp" "$dir/csingle.inp" || fail "--cohesive: gathered .inp differs between 3 ranks and 1 rank"

# A malformed STL file: read by one rank only (the third file, rank 2 of 3).
printf 'solid broken\n facet normal 0 0 1\n  outer loop\n   vertex 0 0\n' > "$dir/bad.stl"
scene "$dir/bad_scene.json" "$dir/bad.stl"
mkdir "$dir/out"
start=$(date +%s)
run_mpi 3 "$cisamr" mesh "$dir/bad_scene.json" -o "$dir/out/m.pvtu" --partitions 4 -q 2> "$dir/err.txt"
rc=$?
[ $rc -eq 2 ] || { cat "$dir/err.txt"; fail "bad STL: exit status $rc, expected 2"; }
[ $(( $(date +%s) - start )) -lt 20 ] || fail "bad STL: too slow"
[ "$(grep -c 'cisamr: error: .*bad.stl' "$dir/err.txt")" = 1 ] || { cat "$dir/err.txt"; fail "bad STL: message not printed exactly once"; }
[ -z "$(ls -A "$dir/out")" ] || fail "bad STL: files left behind: $(ls -A "$dir/out")"

# A missing STL file: the scene's field is named, as the sequential reader names it.
scene "$dir/missing_scene.json" "$dir/missing.stl"
run_mpi 2 "$cisamr" mesh "$dir/missing_scene.json" -o "$dir/out/m.pvtu" --partitions 2 -q 2> "$dir/err2.txt"
rc=$?
[ $rc -eq 2 ] || { cat "$dir/err2.txt"; fail "missing STL: exit status $rc"; }
"$cisamr" mesh "$dir/missing_scene.json" -o "$dir/out/s.vtu" -q 2> "$dir/err3.txt"
[ "$(grep 'cisamr: error' "$dir/err2.txt")" = "$(cat "$dir/err3.txt")" ] ||
  { cat "$dir/err2.txt" "$dir/err3.txt"; fail "missing STL: parallel and sequential messages differ"; }
grep -q 'inclusions\[5\].file: cannot read' "$dir/err2.txt" || { cat "$dir/err2.txt"; fail "missing STL message"; }
echo "cli_test3: all passed"
