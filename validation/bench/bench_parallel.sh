#!/bin/bash
# Scaling study of the parallel mesher (not a test): wall time and phase times of
# `cisamr mesh` for 1 and 2 MPI ranks, and for 1 to 64 partitions on one rank, in 2D and 3D.
# Every run's checksum is compared with the sequential run's (`cisamr mesh` without
# --partitions). Figures: validation/bench/SCALING.md.
#   validation/bench/bench_parallel.sh BUILD/bin/cisamr [2d|3d|e4|all]
# Environment: OUT (default /tmp/cisamr_bench_parallel), REPS (runs per configuration, the
# median is kept; default 3), PARTS1 / PARTS2 (partition counts on 1 / 2 ranks), RANKS
# (more rank counts, one partition per rank; for machines with more cores; each also runs
# that many sequential runs at once, to tell what the machine loses with its cores busy
# from what the mesher loses).
# Run it on an idle machine: timings taken while something else compiles are worthless.
set -eu
cisamr=$(realpath "$1")
which=${2:-all}
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../.." && pwd)
out=${OUT:-/tmp/cisamr_bench_parallel}
reps=${REPS:-3}
mkdir -p "$out"
cd "$out"
mpi="mpiexec --oversubscribe --allow-run-as-root"

# 2D: non-overlapping circles of two phases, ~30 % area fraction, on a grid hash (seeded).
make_2d() {  # CIRCLES SIDE LEVELS
python3 - "$@" > scene2d.json <<'PY'
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
}

# Before each run, wait (up to 15 minutes) until no other process uses more than 20 % of a
# core, so that shared machines give honest figures; runs that had to go on anyway are
# listed in busy.txt. WAIT_IDLE=0 skips the wait.
wait_idle() {
  [ "${WAIT_IDLE:-1}" = 1 ] || return 0
  local t
  for t in $(seq 1 180); do
    [ -z "$(top -b -n 2 -d 0.5 | awk '/^top -/{i++} i==2 && /^ *[0-9]+ / && $9+0 > 20')" ] && return 0
    sleep 5
  done
  echo "$1" >> busy.txt
}

# One configuration, REPS times: NAME RANKS SCENE [cisamr mesh options...]. RANKS 0: the
# sequential mesher. Keeps every report (NAME.RUN.json) and the peak RSS of 1-process runs.
run() {
  local name=$1 ranks=$2 scene=$3; shift 3
  for r in $(seq 1 "$reps"); do
    wait_idle "$name.$r"
    if [ "$ranks" = 0 ] || [ "$ranks" = 1 ]; then
      /usr/bin/time -f "%M" -o "$name.$r.rss" "$cisamr" mesh "$scene" -o "$name.vtu" --report "$name.$r.json" -q "$@"
    else
      $mpi -n "$ranks" "$cisamr" mesh "$scene" -o "$name.pvtu" --report "$name.$r.json" -q "$@"
    fi
    # The output on disk before the next run: written back during it (E4: 1 GB, 30 s on),
    # it slowed that run's partitions by up to 60 %.
    sync
  done
  rm -f "$name".vtu "$name".pvtu "$name"_*.vtu
}

# P sequential runs at once, REPS times: NAME P SCENE [options...]. A machine whose cores
# share caches, memory bandwidth or a turbo budget runs each slower than one alone: the
# median over the copies against the sequential run's is that loss, which no mesher avoids
# (a lent 16-core machine at 876a47f lost about a quarter from 4 busy cores on; SCALING.md).
# Needs P times the sequential run's memory.
run_copies() {
  local name=$1 copies=$2 scene=$3; shift 3
  local pids pid
  for r in $(seq 1 "$reps"); do
    wait_idle "$name.$r"
    pids=()
    for k in $(seq 1 "$copies"); do
      "$cisamr" mesh "$scene" -o "$name.$k.vtu" --report "$name.$r.$k.json" -q "$@" &
      pids+=($!)
    done
    for pid in "${pids[@]}"; do wait "$pid" || { echo "$name.$r: a sequential copy failed" >&2; exit 1; }; done
    rm -f "$name".*.vtu
    sync
  done
}

# NAME SCENE PARTS1 PARTS2 [options...]: the sequential run, 1 rank with PARTS1, 2 ranks
# with PARTS2, then the table, and what N ranks would take from each 1-rank run with N > 1
# partitions (project_ranks.py: NAME-proj-nN.txt).
study() {
  local tag=$1 scene=$2 parts1=$3 parts2=$4; shift 4
  run "$tag-seq" 0 "$scene" "$@"
  for n in $parts1; do run "$tag-r1-n$n" 1 "$scene" --partitions "$n" "$@"; done
  for n in $parts2; do run "$tag-r2-n$n" 2 "$scene" --partitions "$n" "$@"; done
  for p in ${RANKS:-}; do
    run "$tag-r$p-n$p" "$p" "$scene" --partitions "$p" "$@"
    run_copies "$tag-copies$p" "$p" "$scene" "$@"
  done
  python3 "$here/bench_table.py" "$tag" "$reps" > "$tag.md"
  cat "$tag.md"
  for p in ${RANKS:-}; do
    python3 - "$tag" "$p" <<'PY'
import glob, json, statistics, sys
tag, p = sys.argv[1], sys.argv[2]
alone = statistics.median(json.load(open(f))["total_s"] for f in glob.glob(tag + "-seq.*.json"))
busy = statistics.median(json.load(open(f))["total_s"] for f in glob.glob("%s-copies%s.*.json" % (tag, p)))
ranks = statistics.median(json.load(open(f))["total_s"] for f in glob.glob("%s-r%s-n%s.*.json" % (tag, p, p)))
sums = {json.load(open(f))["checksum"] for f in glob.glob(tag + "-seq.*.json") + glob.glob("%s-copies%s.*.json" % (tag, p))}
if len(sums) != 1:
    print("%s sequential runs at once: CHECKSUMS DIFFER %s" % (p, sorted(sums)))
print("%s ranks: %.2f s, efficiency %.3f; %s sequential runs at once %.2f s each against %.2f s alone "
      "(the machine keeps %.3f of a core), efficiency against them %.3f"
      % (p, ranks, alone / (int(p) * ranks), p, busy, alone, alone / busy, busy / (int(p) * ranks)))
PY
  done
  for n in $parts1; do
    [ "$n" -gt 1 ] || continue
    python3 "$here/project_ranks.py" --sequential "$tag-seq".*.json --partitions "$tag-r1-n$n".*.json > "$tag-proj-n$n.txt"
    echo "projected from $tag-r1-n$n: $(head -1 "$tag-proj-n$n.txt")"
  done
}

if [ "$which" = 2d ] || [ "$which" = all ]; then
  make_2d 4000 400 2
  study 2d scene2d.json "${PARTS1:-1 2 4 8 16 32 64}" "${PARTS2:-2 4 8 16}"
fi
if [ "$which" = 3d ] || [ "$which" = all ]; then
  study 3d "$repo/data/bench/spheres300.json" "${PARTS1:-1 2 4 8 16 32 64}" "${PARTS2:-2 4 8}"
fi
if [ "$which" = e4 ] || [ "$which" = all ]; then
  # The paper's example 4 (1,418 silica spheres, 800 µm cube) at h = 16 µm, levels 2,
  # Lmax 2: 21 M tetrahedra, 3.1 GB sequentially.
  python3 -c "
import json, sys
d = json.load(open('$repo/data/paper/e4_silica_spheres.json')); d['mesh']['h'] = 16.0
json.dump(d, open('e4_spec.json', 'w'))"
  "$cisamr" pack e4_spec.json -o e4.json -q
  study e4 e4.json "${PARTS1:-1 2 8 64}" "${PARTS2:-2 4}" --extra-levels 0
fi
