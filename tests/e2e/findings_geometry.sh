#!/bin/bash
# Geometry at the edges of the domain, through the built binary, sequentially and on the
# parallel path (--partitions, `partition`, and mpiexec when given):
#  - inclusions far outside the domain cost nothing (the effective-levels bucket grid is
#    the domain's, not the inclusions' box);
#  - a surface reaching far out of the domain is sampled for loads only inside it;
#  - every path refuses the same invalid shapes with exit 2 and the same one-line message.
# usage: findings_geometry.sh CISAMR [MPIEXEC]
set -u
cisamr=$1 mpiexec=${2:-}
. "$(dirname "$0")/common.sh"
cd "$dir" || exit 1

scene2() {  # NAME INCLUSIONS: a 10×10 domain
  cat > "$1.json" << END
{"format": "cisamr-scene/1", "dimension": 2, "domain": {"min": [0, 0], "max": [10, 10]},
 "mesh": {"h": 1, "levels": 1}, "phases": [{"id": 1, "name": "m"}, {"id": 2, "name": "p"}],
 "matrix_phase": 1, "inclusions": [$2]}
END
}
scene3() {  # NAME H INCLUSIONS: the unit cube
  cat > "$1.json" << END
{"format": "cisamr-scene/1", "dimension": 3, "domain": {"min": [0, 0, 0], "max": [1, 1, 1]},
 "mesh": {"h": $2, "levels": 0}, "phases": [{"id": 1, "name": "m"}, {"id": 2, "name": "p"}],
 "matrix_phase": 1, "inclusions": [$3]}
END
}
# Every way of meshing or partitioning NAME: "label|command" lines.
paths() {
  echo "sequential|$cisamr mesh $1.json -o $1.seq.vtu -q"
  echo "--partitions 2|$cisamr mesh $1.json -o $1.par.vtu -q --partitions 2"
  echo "partition|$cisamr partition $1.json -n 2 -o $1.part.json -q"
  [ -n "$mpiexec" ] && echo "mpiexec -n 2|$mpiexec -n 2 --oversubscribe --allow-run-as-root $cisamr mesh $1.json -o $1.mpi.vtu -q"
}

# --- Inclusions far outside: quick and accepted, like one just outside. ---------------------
inside='{"shape": "circle", "center": [5, 5], "radius": 2, "phase": 2}'
for far in 12 3e4 1e5 1e20; do
  scene2 "far$far" "$inside, {\"shape\": \"circle\", \"center\": [$far, $far], \"radius\": 1, \"phase\": 2}"
  while IFS='|' read -r label command; do
    timeout 20 $command 2> "$dir/err"; rc=$?
    [ $rc -eq 0 ] || { cat "$dir/err"; fail "a circle at ($far, $far), $label: exit $rc"; }
  done < <(paths "far$far")
done

# --- A surface far larger than the domain: bounded memory on every path. ---------------------
# Sampled whole, the sphere's load takes about 800 MB; inside the cube it is nothing.
scene3 sphere60 0.25 '{"shape": "sphere", "center": [0.5, 0.5, 0.5], "radius": 60, "phase": 2}'
while IFS='|' read -r label command; do
  [[ $label == mpiexec* ]] && continue  # mpiexec itself needs more address space
  (ulimit -v 400000; timeout 20 $command) 2> "$dir/err"; rc=$?
  [ $rc -eq 0 ] || { cat "$dir/err"; fail "a sphere of radius 60, $label: exit $rc"; }
done < <(paths sphere60)

# --- The same answer on every path. -----------------------------------------------------------
same_answer() {  # NAME EXPECTED_EXIT [MESSAGE]
  local name=$1 expected=$2 message=${3:-} label command rc
  while IFS='|' read -r label command; do
    timeout 60 $command > /dev/null 2> "$dir/err"
    rc=$?
    [ $rc -eq "$expected" ] || { cat "$dir/err"; fail "$name, $label: exit $rc, expected $expected"; }
    if [ -n "$message" ]; then
      grep -qxF "cisamr: error: $name.json: $message" "$dir/err" || { cat "$dir/err"; fail "$name, $label: not the message '$message'"; }
      [ "$(grep -c 'error' "$dir/err")" -ge 1 ] && [ "$(grep -c 'internal' "$dir/err")" -eq 0 ] \
        || fail "$name, $label: an internal error"
    fi
  done < <(paths "$name")
}
scene2 poly4 '{"shape": "polygon", "vertices": [[20, 20], [20, 20], [20, 20], [20, 20]], "phase": 2}'
same_answer poly4 2 'inclusions[0].vertices: a polygon needs at least 3 distinct vertices'
scene2 open_nurbs '{"shape": "nurbs", "degree": 2, "knots": [0, 0, 0, 0.5, 1, 1, 1],
  "control_points": [[2, 2], [8, 2], [8, 8], [2, 8]], "phase": 2}'
same_answer open_nurbs 2 'inclusions[0].control_points: curve is not closed (C(start) != C(end))'
# A cylinder far wider than everything: whatever the sequential mesher answers, every path.
scene3 wide_cylinder 0.25 '{"shape": "cylinder", "start": [0.5, 0.5, 0.2], "end": [0.5, 0.5, 0.8], "radius": 1.2e29, "phase": 2}'
timeout 60 "$cisamr" mesh wide_cylinder.json -o wide.vtu -q 2> "$dir/err"
same_answer wide_cylinder $? "$(sed -n 's/^cisamr: error: wide_cylinder.json: //p' "$dir/err")"
echo "all passed"
