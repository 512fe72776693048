#!/bin/bash
# Where outputs go (lib/io/README.md, "Output paths"), through the built binary: a symlinked
# output replaces its target and stays a link; `-` and /dev/stdout carry only the data on
# standard output (summaries move to standard error); SIGTERM or SIGINT in the middle of a
# write leaves neither a temporary nor the final file (also under mpiexec); a run whose second
# output fails leaves none of its outputs.
# usage: output_paths.sh CISAMR SOURCE_DIR [MPIEXEC]
set -u
cisamr=$1 source_dir=$2 mpiexec=${3:-}
composite=$source_dir/data/examples/composite.json
spheres=$source_dir/data/examples/spheres3d.json
. "$(dirname "$0")/common.sh"
cd "$dir" || exit 1  # so that a file wrongly named `-` would land here
is_json() { python3 -c 'import json, sys; json.load(open(sys.argv[1]))' "$1" 2> /dev/null; }
# Hidden files anywhere under the folder: a temporary left behind.
no_hidden() { local left; left=$(find "$1" -name '.*' ! -name . | head -3); [ -z "$left" ] || fail "$2: left behind: $left"; }
# composite.json's mesh passes its certificate with this tolerance (exit 0, not 3).
passing=(--scene "$composite" --fidelity-tolerance 0.2)
run_mpi() { local n=$1; shift; timeout 60 "$mpiexec" -n "$n" --oversubscribe --allow-run-as-root "$@"; }

# --- A symlinked output: the target (in another folder) is replaced, the link stays. --------
mkdir -p "$dir/link/out" "$dir/link/scratch"
echo old > "$dir/link/scratch/mesh.vtu"
ln -s ../scratch/mesh.vtu "$dir/link/out/mesh.vtu"
ln -s ../scratch/report.json "$dir/link/out/report.json"  # dangling: created through the link
"$cisamr" mesh "$composite" -o "$dir/link/out/mesh.vtu" --report "$dir/link/out/report.json" -q \
  || fail "mesh through a symlink"
[ -L "$dir/link/out/mesh.vtu" ] || fail "the output symlink was replaced by a file"
[ -L "$dir/link/out/report.json" ] || fail "the report symlink was replaced by a file"
grep -q UnstructuredGrid "$dir/link/scratch/mesh.vtu" || fail "the symlink's target was not updated"
is_json "$dir/link/scratch/report.json" || fail "the report was not written through the dangling link"
no_hidden "$dir/link" "mesh through a symlink"

# --- `-`: the data alone on standard output. ----------------------------------------------
"$cisamr" mesh "$composite" -o "$dir/c.vtu" --report - > "$dir/report.out" 2> "$dir/report.err" \
  || fail "mesh --report -"
is_json "$dir/report.out" || { head -c 300 "$dir/report.out"; fail "mesh --report -: standard output is not JSON"; }
grep -q 'max aspect ratio' "$dir/report.err" || fail "mesh --report -: the summary is not on standard error"
[ ! -e "$dir/-" ] || fail "mesh --report -: a file named '-' was written"

"$cisamr" mesh "$composite" -o - --format msh > "$dir/mesh.out" 2> "$dir/mesh.err" || fail "mesh -o - --format msh"
head -1 "$dir/mesh.out" | grep -qx '\$MeshFormat' || fail "mesh -o -: standard output does not start with \$MeshFormat"
grep -q 'max aspect ratio' "$dir/mesh.err" || fail "mesh -o -: the summary is not on standard error"
"$cisamr" mesh "$composite" -o - 2> "$dir/mesh.err" > /dev/null
[ $? -eq 2 ] && grep -q 'name the mesh format' "$dir/mesh.err" || fail "mesh -o - without a format: not a clear error"

"$cisamr" certify "$dir/c.vtu" "${passing[@]}" --json - > "$dir/cert.out" 2> "$dir/cert.err" \
  || fail "certify --json -"
is_json "$dir/cert.out" || { head -c 300 "$dir/cert.out"; fail "certify --json -: standard output is not JSON"; }
[ -s "$dir/cert.err" ] || fail "certify --json -: no summary on standard error"

"$cisamr" pack "$source_dir/data/bench/spheres300.pack.json" -o - > "$dir/scene.out" 2> "$dir/pack.err" \
  || fail "pack -o -"
is_json "$dir/scene.out" || fail "pack -o -: standard output is not JSON"
grep -q 'packed' "$dir/pack.err" || fail "pack -o -: the summary is not on standard error"

# --- /dev/stdout and devices: written through, never replaced. ----------------------------
# First through links of our own (a wrong binary replaces only the link), and only then, run
# as root, the system's /dev/stdout and /dev/null themselves.
ln -s /proc/self/fd/1 "$dir/to_stdout.json"
"$cisamr" certify "$dir/c.vtu" "${passing[@]}" --json "$dir/to_stdout.json" -q > "$dir/via_link.out" \
  || fail "--json LINK-TO-FD-1"
[ -L "$dir/to_stdout.json" ] && is_json "$dir/via_link.out" || fail "--json LINK-TO-FD-1: link replaced or no JSON"
ln -s /dev/null "$dir/to_null.json"
"$cisamr" certify "$dir/c.vtu" "${passing[@]}" --json "$dir/to_null.json" -q || fail "--json LINK-TO-/dev/null"
[ -L "$dir/to_null.json" ] && [ -c /dev/null ] || fail "--json LINK-TO-/dev/null: link or device replaced"
"$cisamr" certify "$dir/c.vtu" "${passing[@]}" --json /dev/null -q || fail "--json /dev/null"
if [ ! -c /dev/null ]; then
  rm -f /dev/null && mknod -m 666 /dev/null c 1 3  # repair what the run broke
  fail "--json /dev/null replaced the device"
fi
if [ -L /dev/stdout ]; then
  "$cisamr" certify "$dir/c.vtu" "${passing[@]}" --json /dev/stdout -q > "$dir/devstdout.out" \
    || fail "certify --json /dev/stdout"
  if [ ! -L /dev/stdout ]; then
    rm -f /dev/stdout && ln -s /proc/self/fd/1 /dev/stdout  # repair what the run broke
    fail "certify --json /dev/stdout replaced the /dev/stdout symlink"
  fi
  is_json "$dir/devstdout.out" || fail "certify --json /dev/stdout: not JSON"
  # A pipe, and the summary on standard error.
  "$cisamr" certify "$dir/c.vtu" "${passing[@]}" --json /dev/stdout 2> /dev/null \
    | python3 -c 'import json, sys; json.loads(sys.stdin.read())' 2> /dev/null \
    || fail "certify --json /dev/stdout into a pipe: not JSON alone"
fi

# --- SIGTERM in the middle of a long write: no temporary, no final file. -------------------
# 5.0 M tets: writing the .msh takes about 0.75 s here (at h = 0.0125 it took 0.38 s, and
# the 0.3 s delay below once outlasted it on a quiet machine).
cat > "$dir/big.json" << 'EOF'
{"format": "cisamr-scene/1", "dimension": 3, "domain": {"min": [0, 0, 0], "max": [1, 1, 1]},
 "mesh": {"h": 0.01}, "inclusions": [{"shape": "sphere", "center": [0.5, 0.5, 0.5], "radius": 0.3}]}
EOF
# Starts the command in the background, waits until its temporary appears (the write has
# begun), sleeps DELAY, sends SIGTERM (or $SIGNAL) to PID; checks that the process died of it
# and left nothing in OUTDIR. usage: [SIGNAL=INT] kill_mid_write LABEL OUTDIR DELAY COMMAND...
kill_mid_write() {
  local label=$1 outdir=$2 delay=$3; shift 3
  mkdir -p "$outdir"
  "$@" > /dev/null 2>&1 &
  local pid=$! waited=0
  until [ -n "$(find "$outdir" -name '.*.tmp.*' | head -1)" ]; do
    kill -0 "$pid" 2> /dev/null || { wait "$pid"; fail "$label: ended before writing (status $?)"; }
    sleep 0.02
    waited=$((waited + 1))
    [ $waited -lt 6000 ] || { kill -KILL "$pid"; fail "$label: no temporary after 120 s"; }
  done
  sleep "$delay"
  kill -"${SIGNAL:-TERM}" "$pid"
  wait "$pid"
  local rc=$?
  [ $rc -ne 0 ] || fail "$label: finished before SIGTERM (delay $delay s too long for this machine)"
  local left; left=$(ls -A "$outdir")
  # Under mpiexec the signal reaches the ranks only after mpiexec forwards it: the run may
  # have committed its output in between. Then the file is complete, not a leftover; a
  # temporary or a file that does not read back is still a failure.
  if [ -n "$left" ] && [ -n "${ACCEPT_COMMITTED:-}" ] && [ "$left" = "$ACCEPT_COMMITTED" ] &&
     "$cisamr" certify "$outdir/$left" -q > /dev/null 2>&1; then
    left=""
  fi
  [ -z "$left" ] || fail "$label: SIG${SIGNAL:-TERM} after $delay s left: $left"
}
for delay in 0 0.2; do
  kill_mid_write "SIGTERM, .msh" "$dir/kill_msh_$delay" "$delay" "$cisamr" mesh "$dir/big.json" -o "$dir/kill_msh_$delay/big.msh" -q
done
kill_mid_write "SIGTERM, .vtu" "$dir/kill_vtu" 0 "$cisamr" mesh "$dir/big.json" -o "$dir/kill_vtu/big.vtu" -q
# SIGINT (Ctrl-C): a background job of a script starts with SIGINT ignored; perl restores it.
SIGNAL=INT kill_mid_write "SIGINT, .msh" "$dir/kill_int" 0 \
  perl -e '$SIG{INT} = "DEFAULT"; exec @ARGV' -- "$cisamr" mesh "$dir/big.json" -o "$dir/kill_int/big.msh" -q
# Killed before writing: nothing at all.
mkdir "$dir/kill_early"
"$cisamr" mesh "$dir/big.json" -o "$dir/kill_early/big.vtu" -q & pid=$!
sleep 0.5; kill -TERM $pid; wait $pid
[ -z "$(ls -A "$dir/kill_early")" ] || fail "SIGTERM before writing left: $(ls -A "$dir/kill_early")"

# --- A failing second output: no first output either. --------------------------------------
mkdir "$dir/partial"
"$cisamr" partition "$composite" -n 4 -o "$dir/partial/parts.json" --svg "$dir/partial/missing/parts.svg" -q \
  2> "$dir/partial.err"
[ $? -eq 2 ] || fail "partition with an unwritable --svg: exit status, expected 2"
grep -q "missing/parts.svg: cannot write" "$dir/partial.err" || fail "partition: the error does not name the svg"
[ -z "$(ls -A "$dir/partial")" ] || fail "partition: a failed --svg left $(ls -A "$dir/partial")"
"$cisamr" mesh "$composite" -o "$dir/partial/mesh.vtu" --report "$dir/partial/missing/r.json" -q 2> /dev/null
[ $? -eq 2 ] || fail "mesh with an unwritable --report: exit status, expected 2"
[ -z "$(ls -A "$dir/partial")" ] || fail "mesh: a failed --report left $(ls -A "$dir/partial")"
"$cisamr" certify "$dir/c.vtu" "${passing[@]}" --json "$dir/partial/cert.json" --html "$dir/partial/missing/c.html" -q 2> /dev/null
[ $? -eq 2 ] || fail "certify with an unwritable --html: exit status, expected 2"
[ -z "$(ls -A "$dir/partial")" ] || fail "certify: a failed --html left $(ls -A "$dir/partial")"
"$cisamr" mesh "$composite" -o "" -q 2> "$dir/empty.err"
[ $? -eq 2 ] && grep -q 'empty' "$dir/empty.err" || { cat "$dir/empty.err"; fail "-o '': not an 'empty path' error"; }

# --- Under mpiexec: the same on every rank. ------------------------------------------------
if [ -n "$mpiexec" ]; then
  mkdir "$dir/mpi_partial"
  run_mpi 2 "$cisamr" mesh "$spheres" -o "$dir/mpi_partial/m.pvtu" --report "$dir/mpi_partial/missing/r.json" -q \
    2> /dev/null
  [ $? -eq 2 ] || fail "mpiexec, unwritable --report: exit status, expected 2"
  [ -z "$(ls -A "$dir/mpi_partial")" ] || fail "mpiexec: a failed --report left $(ls -A "$dir/mpi_partial")"
  ACCEPT_COMMITTED=big.msh kill_mid_write "mpiexec, SIGTERM, --gather" "$dir/kill_mpi" 0 \
    "$mpiexec" -n 2 --oversubscribe --allow-run-as-root "$cisamr" mesh "$dir/big.json" -o "$dir/kill_mpi/big.msh" --gather -q
fi
echo "output paths: all checks passed"
