#!/usr/bin/env bash
# The partitions' costs (issue #15) read back by Python's json, not the code that wrote them:
# `cisamr partition` and `cisamr mesh --partitions` (and under mpiexec, where rank 0
# partitions and broadcasts) give the same boxes and costs; the boxes tile the domain; in 3D
# each cost lies between the load and the load plus the weighted load of everything, and the
# summary and report spreads are the parts' own; in 2D the partition file has no costs and
# the report's equal the loads. A 3D in-memory run reports its decisions near faces exchanged.
# Usage: partition_costs.sh CISAMR SOURCE_DIR [MPIEXEC]
set -u
cisamr=$1
source_dir=$2
mpiexec=${3:-}
. "$(dirname "$0")/common.sh"

check() {  # SCENE N PARTS.json REPORT.json
  python3 - "$@" <<'PY' || return 1
import json, math, sys
scene, n, parts_path, report_path = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
parts, report = json.load(open(parts_path)), json.load(open(report_path))
dim = parts["dimension"]
boxes = [(tuple(p["lattice_min"]), tuple(p["lattice_max"])) for p in parts["parts"]]
meshed = [(tuple(p["lattice_min"]), tuple(p["lattice_max"])) for p in report["partitions"]]
assert len(boxes) == n and boxes == meshed, ("boxes differ", boxes, meshed)
volume = sum(math.prod(hi[d] - lo[d] for d in range(dim)) for lo, hi in boxes)
assert volume == math.prod(parts["lattice_cells"]), "the boxes do not tile the domain"
summary, load = parts["summary"], report["load"]
if dim == 3:
    w = summary["ghost_weight"]
    assert 0 < w < 1 and summary["ghost_cells"] >= 1, summary
    total = summary["total_load"]
    for p, q in zip(parts["parts"], report["partitions"]):
        assert p["load"] <= p["cost"] <= p["load"] + w * total * (1 + 1e-12), p
        assert p["cost"] == q["cost"], (p["cost"], q["cost"])
    costs = [p["cost"] for p in parts["parts"]]
    assert any(c > p["load"] for c, p in zip(costs, parts["parts"])), "no box pays for its ghost"
    assert summary["max_cost"] == max(costs) == load["cost_max"]
    assert math.isclose(summary["mean_cost"], sum(costs) / n, rel_tol=1e-12)
    assert math.isclose(load["cost_imbalance"], max(costs) / (sum(costs) / n), rel_tol=1e-12)
    # In memory, the forest and the decisions near the boxes' faces were exchanged, with a
    # narrower ghost than the partitioner's cost counts (its margins are the recomputing ones):
    # the ghost cubes of the boxes with inclusions near took their owners' trees.
    assert report["near_faces"] == "exchanged" and report["exchanged_nodes"] > 0, report.get("near_faces")
    ghost = sum(q["ghost_coarse_cells"] for q in report["partitions"])
    assert 0 < report["exchanged_cubes"] <= ghost, (report["exchanged_cubes"], ghost)
    assert 0 <= report["replaced_cubes"] <= ghost, report["replaced_cubes"]
    assert report["timings_s"]["exchange"]["max"] >= 0, report["timings_s"]
else:
    assert "cost" not in parts["parts"][0] and "max_cost" not in summary, summary
    assert load["cost_max"] == load["max"] and load["cost_imbalance"] == load["imbalance"], load
    assert all(q["cost"] == q["load"] for q in report["partitions"])
    assert "near_faces" not in report, "a 2D report names the 3D exchange"
PY
}

cat > "$dir/circles.json" <<'JSON'
{"format": "cisamr-scene/1", "dimension": 2, "domain": {"min": [0, 0], "max": [40, 40]},
 "mesh": {"h": 1, "levels": 1}, "inclusions": [
  {"shape": "circle", "center": [6, 7], "radius": 3}, {"shape": "circle", "center": [20, 21], "radius": 4},
  {"shape": "circle", "center": [33, 9], "radius": 2.5}, {"shape": "circle", "center": [11, 31], "radius": 3.5},
  {"shape": "circle", "center": [30, 32], "radius": 3}]}
JSON
for scene in "$source_dir/data/examples/spheres3d.json" "$dir/circles.json"; do
  [ -f "$scene" ] || { fail_and_go_on "missing $scene"; continue; }
  name=$(basename "$scene" .json)
  "$cisamr" partition "$scene" -n 6 -o "$dir/$name.parts.json" -q || fail_and_go_on "$name: partition failed"
  "$cisamr" mesh "$scene" -o "$dir/$name.pvtu" --partitions 6 -q --report "$dir/$name.r1.json" || fail_and_go_on "$name: mesh failed"
  check "$scene" 6 "$dir/$name.parts.json" "$dir/$name.r1.json" || fail_and_go_on "$name: one process"
  if [ -n "$mpiexec" ]; then
    "$mpiexec" --oversubscribe --allow-run-as-root -n 2 "$cisamr" mesh "$scene" -o "$dir/$name.m.pvtu" --partitions 6 -q \
        --report "$dir/$name.r2.json" || fail_and_go_on "$name: mpiexec mesh failed"
    check "$scene" 6 "$dir/$name.parts.json" "$dir/$name.r2.json" || fail_and_go_on "$name: 2 ranks"
  fi
done

[ "$failures" -eq 0 ] && echo "partition_costs: all checks passed"
exit $((failures > 0))
