#!/bin/bash
# Scaling study of the parallel 2D mesher (not a test): wall time and phase times of
# `cisamr mesh` for 1 and 2 MPI ranks, and for 1 to 64 partitions on one rank.
#   validation/bench/bench_parallel.sh BUILD/bin/cisamr [CIRCLES] [SIDE] [LEVELS]
# Writes the scene, the reports and a Markdown table to ${OUT:-/tmp/cisamr_bench_parallel}.
set -eu
cisamr=$(realpath "$1")
circles=${2:-4000} side=${3:-400} levels=${4:-2}
out=${OUT:-/tmp/cisamr_bench_parallel}
mkdir -p "$out"
cd "$out"
mpi="mpiexec --oversubscribe --allow-run-as-root"

# Non-overlapping circles of two phases, ~30 % area fraction, on a grid hash (seeded).
python3 - "$circles" "$side" "$levels" > scene.json <<'PY'
import json, math, random, sys
n, L, levels = int(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3])
random.seed(7)
mean_r = math.sqrt(0.30 * L * L / (n * math.pi))
cell = 3 * mean_r
m = int(L / cell) + 1
bucket = {}
placed = []
tries = 0
while len(placed) < n and tries < 200 * n:
    tries += 1
    r = mean_r * (0.7 + 0.6 * random.random())
    x, y = random.random() * L, random.random() * L
    bi, bj = int(x / cell), int(y / cell)
    ok = all(math.hypot(x - placed[k][0], y - placed[k][1]) >= r + placed[k][2] + 0.5
             for j in range(bj - 1, bj + 2) for i in range(bi - 1, bi + 2) for k in bucket.get((i, j), []))
    if not ok:
        continue
    bucket.setdefault((bi, bj), []).append(len(placed))
    placed.append((x, y, r))
scene = {"format": "cisamr-scene/1", "dimension": 2,
         "domain": {"min": [0, 0], "max": [L, L]}, "mesh": {"h": 1.0, "levels": levels},
         "phases": [{"id": 1, "name": "matrix"}, {"id": 2, "name": "particle"}, {"id": 3, "name": "fibre"}],
         "inclusions": [{"shape": "circle", "center": [round(x, 6), round(y, 6)], "radius": round(r, 6),
                         "phase": 2 + (k % 2)} for k, (x, y, r) in enumerate(placed)]}
print(json.dumps(scene))
PY

run() {  # name ranks command...
  local name=$1 ranks=$2; shift 2
  if [ "$ranks" = 0 ]; then "$cisamr" "$@" --report "$name.json" -q; else $mpi -n "$ranks" "$cisamr" "$@" --report "$name.json" -q; fi
}
run seq 0 mesh scene.json -o seq.vtu
for n in 1 2 4 8 16 32 64; do run "r1_n$n" 0 mesh scene.json -o "r1_n$n.vtu" --partitions "$n"; done
for n in 2 4 8 16; do run "r2_n$n" 2 mesh scene.json -o "r2_n$n.pvtu" --partitions "$n"; done
run r1_n8_fixed 0 mesh scene.json -o r1_n8_fixed.vtu --partitions 8 --fixed-ghost
run r2_n8_gather 2 mesh scene.json -o r2_n8_gather.vtu --partitions 8 --gather

python3 - > table.md <<'PY'
import json, glob
rows = ["seq"] + [f"r1_n{n}" for n in (1, 2, 4, 8, 16, 32, 64)] + [f"r2_n{n}" for n in (2, 4, 8, 16)] + ["r1_n8_fixed", "r2_n8_gather"]
seq = json.load(open("seq.json"))
phases = ["partition", "ghost", "oracle", "samr", "radapt", "subdivide", "assemble", "merge", "write"]
print(f"scene: {len(json.load(open('scene.json'))['inclusions'])} circles, {seq['elements']} triangles, checksum {seq['checksum']}\n")
print("| run | ranks | N | total s | " + " | ".join(f"{p} max (min)" for p in phases) + " | load max/mean | coarse cells meshed / domain | checksum = seq |")
print("|" + "---|" * (len(phases) + 7))
domain = seq["algorithm"]["coarse_cells"]
for r in rows:
    j = json.load(open(r + ".json"))
    t = j["timings_s"]
    if r == "seq":
        cells = "| " + " | ".join(f"{t[p]['max']:.3f}" if p in t else "-" for p in phases)
        print(f"| {r} | 1 | - | {j['total_s']:.3f} {cells} | - | 1.00 | {'yes'} |")
        continue
    n = len(j["partitions"])
    cells = "| " + " | ".join(f"{t[p]['max']:.3f} ({t[p]['min']:.3f})" for p in phases)
    meshed = sum(p["ghost_coarse_cells"] for p in j["partitions"]) / domain + 1
    print(f"| {r} | {j['ranks']} | {n} | {j['total_s']:.3f} {cells} | {j['load']['imbalance']:.3f} | {meshed:.2f} | {'yes' if j['checksum'] == seq['checksum'] else 'NO'} |")
PY
cat table.md
