#!/usr/bin/env bash
# validation/bench/project_ranks.py on real reports (issue #15: what N ranks would take, from
# runs on one process): two sequential runs and two 4-partition runs of a 3D example. The
# projection reads each partition's kernel parts (`kernel_stages_s`), takes the runs'
# medians, charges the sum over parts of their maxima (at least the slowest partition's
# kernel; in 2D, which exchanges nothing, the slowest partition's), and refuses runs of
# different meshes or a run that was not partitioned.
# Usage: project_ranks.sh CISAMR SOURCE_DIR
set -u
cisamr=$1
source_dir=$2
. "$(dirname "$0")/common.sh"
project="python3 $source_dir/validation/bench/project_ranks.py"
scene=$source_dir/data/examples/spheres3d.json

for i in 1 2; do
  "$cisamr" mesh "$scene" -o "$dir/s.vtu" -q --report "$dir/seq.$i.json" || fail "sequential run $i"
  "$cisamr" mesh "$scene" -o "$dir/p.pvtu" --partitions 4 -q --report "$dir/n4.$i.json" || fail "4 partitions, run $i"
done
$project --sequential "$dir"/seq.*.json --partitions "$dir"/n4.*.json --json > "$dir/p.json" || fail "projection"
python3 - "$dir" <<'PY' || fail "projection's figures"
import json, sys
d = sys.argv[1]
p = json.load(open(d + "/p.json"))
runs = [json.load(open("%s/n4.%d.json" % (d, i))) for i in (1, 2)]
seqs = [json.load(open("%s/seq.%d.json" % (d, i))) for i in (1, 2)]
assert p["partitions"] == 4, p
# Two runs: every median is their mean.
assert abs(p["sequential_s"] - (seqs[0]["total_s"] + seqs[1]["total_s"]) / 2) < 1e-9, p
stages = [[(runs[0]["partitions"][i]["kernel_stages_s"][s] + runs[1]["partitions"][i]["kernel_stages_s"][s]) / 2
           for s in range(4)] for i in range(4)]
waits = sum(max(stages[i][s] for i in range(4)) for s in range(4))
assert abs(p["terms"]["kernel"] - waits) < 1e-9, (p["terms"]["kernel"], waits)
assert p["terms"]["kernel"] >= p["kernel"]["slowest_s"] - 1e-12, p
assert p["kernel"]["waits_over_slowest"] >= 1 - 1e-12, p
assert abs(p["projected_s"] - sum(p["terms"].values())) < 1e-9, p
assert abs(p["efficiency"] - p["sequential_s"] / (4 * p["projected_s"])) < 1e-12, p
assert p["cells_meshed_over_domain"] > 1, p  # a ghost
assert not p["unknown_phases"], p["unknown_phases"]
PY

# 2D (composite.json) exchanges nothing: no parts, the kernel is the slowest partition's.
scene2=$source_dir/data/examples/composite.json
"$cisamr" mesh "$scene2" -o "$dir/s2.vtu" -q --report "$dir/seq2.json" || fail "2D sequential run"
"$cisamr" mesh "$scene2" -o "$dir/p2.pvtu" --partitions 3 -q --report "$dir/n3.json" || fail "2D, 3 partitions"
$project --sequential "$dir/seq2.json" --partitions "$dir/n3.json" --json > "$dir/p2.json" || fail "2D projection"
python3 - "$dir" <<'PY' || fail "2D projection's figures"
import json, sys
d = sys.argv[1]
p, run = json.load(open(d + "/p2.json")), json.load(open(d + "/n3.json"))
assert all("kernel_stages_s" not in q for q in run["partitions"]), run["partitions"]
slowest = max(q["kernel_s"] for q in run["partitions"])
assert p["terms"]["kernel"] == slowest and p["kernel"]["waits_over_slowest"] == 1, p
assert p["partitions"] == 3 and not p["unknown_phases"], p
PY

# Bad input: one line on stderr naming the report and the field, exit code 2, nothing on
# stdout. Runs of two meshes (among the partitions' runs, and against the sequential runs),
# a sequential report as the partitions' run and the reverse, a missing file, not a report.
other=$source_dir/data/examples/stl3d.json
"$cisamr" mesh "$other" -o "$dir/o.pvtu" --partitions 4 -q --report "$dir/other.json" || fail "other scene"
echo '{"format": "something-else"}' > "$dir/alien.json"
refused() {  # WHAT FILE FIELD ARGS...: the projection must refuse ARGS naming FILE and FIELD
  local what=$1 file=$2 field=$3; shift 3
  $project "$@" > "$dir/out.txt" 2> "$dir/err.txt"
  local code=$?
  [ "$code" = 2 ] || fail "$what: exit code $code, not 2"
  [ ! -s "$dir/out.txt" ] || fail "$what: printed a projection: $(cat "$dir/out.txt")"
  [ "$(wc -l < "$dir/err.txt")" = 1 ] || fail "$what: not one line: $(cat "$dir/err.txt")"
  grep -qF "$file: $field:" "$dir/err.txt" || fail "$what: does not name $file and $field: $(cat "$dir/err.txt")"
}
refused "runs of two meshes" "$dir/other.json" checksum \
  --sequential "$dir"/seq.*.json --partitions "$dir/n4.1.json" "$dir/other.json"
refused "another mesh than the sequential runs'" "$dir/other.json" checksum \
  --sequential "$dir"/seq.*.json --partitions "$dir/other.json"
refused "a sequential run as the partitions' run" "$dir/seq.2.json" partitions \
  --sequential "$dir/seq.1.json" --partitions "$dir/seq.2.json"
refused "a partitioned run as the sequential one" "$dir/n4.1.json" partitions \
  --sequential "$dir/n4.1.json" --partitions "$dir/n4.2.json"
refused "a missing file" "$dir/none.json" - --sequential "$dir/none.json" --partitions "$dir/n4.1.json"
refused "not a report" "$dir/alien.json" format --sequential "$dir/seq.1.json" --partitions "$dir/alien.json"
echo "project_ranks: ok"
