#!/usr/bin/env bash
# Progress of `cisamr mesh` when stderr is not a terminal (log mode): plain lines naming the
# phases at the reporting interval, none with -q; under mpiexec only rank 0 prints them.
# Usage: progress.sh CISAMR SOURCE_DIR [MPIEXEC]
set -u
cisamr=$1
source_dir=$2
mpiexec=${3:-}
. "$(dirname "$0")/common.sh"

scene=$source_dir/data/examples/spheres3d.json

# A small interval: a line at (nearly) every phase start.
"$cisamr" mesh "$scene" -o "$dir/a.vtu" --progress-interval 0 2>"$dir/log" >/dev/null || fail_and_go_on "mesh failed"
for phase in read oracle levels samr radapt subdivide write; do
  grep -q "^cisamr: \[[0-9]* s\] $phase" "$dir/log" || fail_and_go_on "no progress line for $phase: $(cat "$dir/log")"
done
grep -q $'\r' "$dir/log" && fail_and_go_on "carriage return in log mode"

# The default interval (5 s): a short run prints none.
"$cisamr" mesh "$scene" -o "$dir/b.vtu" 2>"$dir/log" >/dev/null || fail_and_go_on "mesh failed"
grep -q "^cisamr: \[" "$dir/log" && fail_and_go_on "progress lines within the default interval: $(cat "$dir/log")"

# -q: none.
"$cisamr" mesh "$scene" -o "$dir/c.vtu" -q --progress-interval 0 2>"$dir/log" >/dev/null || fail_and_go_on "mesh -q failed"
[ -s "$dir/log" ] && fail_and_go_on "-q printed: $(cat "$dir/log")"

if [ -n "$mpiexec" ]; then
  # --tag-output prefixes every line with [job,rank]<stream>.
  "$mpiexec" --oversubscribe --allow-run-as-root --tag-output -n 2 "$cisamr" mesh "$scene" -o "$dir/d.pvtu" \
      --progress-interval 0 >"$dir/mpi.out" 2>&1 || fail_and_go_on "mpiexec mesh failed: $(cat "$dir/mpi.out")"
  grep -q "<stderr>: *cisamr: \[" "$dir/mpi.out" || fail_and_go_on "no progress under mpiexec: $(cat "$dir/mpi.out")"
  grep "cisamr: \[" "$dir/mpi.out" | grep -v "^\[[0-9]*,0\]" && fail_and_go_on "progress from a rank other than 0"
  grep -q "cisamr: \[[0-9]* s\] kernel" "$dir/mpi.out" || fail_and_go_on "no kernel phase under mpiexec: $(cat "$dir/mpi.out")"
fi

[ "$failures" -eq 0 ] && echo "progress: all checks passed"
exit $((failures > 0))
