#!/bin/bash
# `cisamr mesh` under mpiexec: partition invariance through the command line (report
# checksums, byte-equal gathered files), .pvtu pieces, and errors on one rank or on all
# ranks ending every rank with one message and exit status 2, never a hang.
# usage: cli_test.sh CISAMR MPIEXEC SCENE
set -u
cisamr=$1 mpiexec=$2 scene=$3
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
run_mpi() { local n=$1; shift; timeout 30 "$mpiexec" -n "$n" --oversubscribe --allow-run-as-root "$@"; }
checksum() { sed -n 's/.*"checksum": "\([0-9a-f]*\)".*/\1/p' "$1"; }

"$cisamr" mesh "$scene" -o "$dir/seq.vtu" --report "$dir/seq.json" -q || fail "sequential run"
ref=$(checksum "$dir/seq.json")
[ -n "$ref" ] || fail "no checksum in the sequential report"

"$cisamr" mesh "$scene" -o "$dir/one.vtu" --partitions 7 --report "$dir/one.json" -q || fail "1 rank, 7 partitions"
[ "$(checksum "$dir/one.json")" = "$ref" ] || fail "1 rank, 7 partitions: checksum differs"

run_mpi 2 "$cisamr" mesh "$scene" -o "$dir/two.pvtu" --partitions 5 --report "$dir/two.json" -q || fail "2 ranks"
[ "$(checksum "$dir/two.json")" = "$ref" ] || fail "2 ranks, 5 partitions: checksum differs"
for f in two.pvtu two_0.vtu two_1.vtu; do [ -f "$dir/$f" ] || fail "missing $f"; done
grep -q 'Piece Source="two_1.vtu"' "$dir/two.pvtu" || fail "the .pvtu does not list piece 1"

# One file gathered on rank 0: byte-equal for any number of ranks with the same partitions.
run_mpi 3 "$cisamr" mesh "$scene" -o "$dir/three.msh" --partitions 6 --gather -q || fail "3 ranks, --gather"
"$cisamr" mesh "$scene" -o "$dir/single.msh" --partitions 6 -q || fail "1 rank, 6 partitions, .msh"
cmp -s "$dir/three.msh" "$dir/single.msh" || fail "gathered .msh differs between 3 ranks and 1 rank"

# One rank cannot write its piece: every rank ends, one message, exit 2, nothing left behind.
mkdir -p "$dir/bad/out_1.vtu/inside"
start=$(date +%s)
run_mpi 2 "$cisamr" mesh "$scene" -o "$dir/bad/out.pvtu" --partitions 3 -q 2> "$dir/err.txt"
rc=$?
[ $rc -eq 2 ] || { cat "$dir/err.txt"; fail "unwritable piece: exit status $rc, expected 2"; }
[ $(( $(date +%s) - start )) -lt 20 ] || fail "unwritable piece: too slow"
[ "$(grep -c 'cisamr: error: .*out_1.vtu: cannot write' "$dir/err.txt")" = 1 ] || { cat "$dir/err.txt"; fail "message not printed exactly once"; }
[ "$(ls -A "$dir/bad")" = "out_1.vtu" ] || fail "files left behind: $(ls -A "$dir/bad")"

# Bad input seen by every rank: one message, exit 2.
run_mpi 2 "$cisamr" mesh "$dir/missing.json" -o "$dir/x.pvtu" -q 2> "$dir/err2.txt"
rc=$?
[ $rc -eq 2 ] || fail "missing scene: exit status $rc"
[ "$(grep -c 'cisamr: error: .*missing.json' "$dir/err2.txt")" = 1 ] || { cat "$dir/err2.txt"; fail "missing scene message"; }

# Fewer partitions than ranks.
run_mpi 2 "$cisamr" mesh "$scene" -o "$dir/y.pvtu" --partitions 1 -q 2> "$dir/err3.txt"
[ $? -eq 2 ] || fail "--partitions 1 on 2 ranks accepted"
grep -q 'cisamr: error: --partitions' "$dir/err3.txt" || { cat "$dir/err3.txt"; fail "--partitions message"; }
echo "cli_test: all passed"
