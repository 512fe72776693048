#!/bin/bash
# Interleaved rounds on the 300-sphere benchmark (not a test): per round one partition, 64
# partitions on one rank with the decisions near faces exchanged and recomputed
# (--no-ghost-exchange), the sequential mesher, and 2 ranks both ways, one after another, so
# that this machine's drift hits every configuration alike. Prints the medians, the ratio of
# 64 partitions to one and the efficiency on 2 ranks per round, every checksum, and the
# cells meshed. Figures: validation/bench/SCALING.md ("Decisions exchanged near faces").
#   validation/bench/ghost_rounds.sh BUILD/bin/cisamr [ROUNDS (default 6)] [SCENE]
# Environment: OUT (default /tmp/cisamr_ghost_rounds).
set -eu
cisamr=$(realpath "$1")
rounds=${2:-6}
here=$(cd "$(dirname "$0")" && pwd)
scene=$(realpath "${3:-$here/../../data/bench/spheres300.json}")
out=${OUT:-/tmp/cisamr_ghost_rounds}
mkdir -p "$out"
cd "$out"
mpi="mpiexec --oversubscribe --allow-run-as-root"
for i in $(seq 1 "$rounds"); do
  "$cisamr" mesh "$scene" -o p.pvtu --partitions 1 -q --report n1.$i.json
  "$cisamr" mesh "$scene" -o p.pvtu --partitions 64 -q --report n64.$i.json
  "$cisamr" mesh "$scene" -o p.pvtu --partitions 64 -q --report n64r.$i.json --no-ghost-exchange
  "$cisamr" mesh "$scene" -o s.vtu -q --report seq.$i.json
  $mpi -n 2 "$cisamr" mesh "$scene" -o q.pvtu -q --report r2.$i.json
  $mpi -n 2 "$cisamr" mesh "$scene" -o q.pvtu -q --report r2r.$i.json --no-ghost-exchange
done
python3 - "$rounds" <<'PY'
import json, statistics as st, sys
n = int(sys.argv[1])
kinds = {'n1': 'one partition', 'n64': '64 partitions, exchanged', 'n64r': '64 partitions, recomputed',
         'seq': 'sequential', 'r2': '2 ranks, exchanged', 'r2r': '2 ranks, recomputed'}
report = lambda k, i: json.load(open(f'{k}.{i}.json'))
total = lambda k, i: report(k, i)['total_s']
print('checksums:', sorted({report(k, i)['checksum'] for k in kinds for i in range(1, n + 1)}))
for k, name in kinds.items():
    times = [total(k, i) for i in range(1, n + 1)]
    print(f'{name}: median {st.median(times):.3f} s, per round {[round(t, 2) for t in times]}, '
          f'peak memory {report(k, 1)["peak_rss_bytes"]["max"] >> 20} MB')
for k in ('n64', 'n64r'):
    r = [total(k, i) / total('n1', i) for i in range(1, n + 1)]
    print(f'{kinds[k]} over one partition: median {st.median(r):.3f}, per round {[round(x, 3) for x in r]}')
for k in ('r2', 'r2r'):
    e = [total('seq', i) / (2 * total(k, i)) for i in range(1, n + 1)]
    print(f'efficiency, {kinds[k]}: median {st.median(e):.3f}, per round {[round(x, 3) for x in e]}')
for k in ('n64', 'n64r', 'r2', 'r2r'):
    r = report(k, 1)
    cells = r['algorithm']['coarse_cells_meshed'] + sum(p['ghost_coarse_cells'] for p in r['partitions'])
    a = r['algorithm']
    print(f'{kinds[k]}: cells meshed / domain {cells / a["coarse_cells_meshed"]:.3f}, leaves {a["leaves"]}, '
          f'r-adaptivity\'s {a["snapping_leaves"]}, guard combinations {a["guard_combinations"]}')
PY
