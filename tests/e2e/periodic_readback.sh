#!/bin/bash
# A periodic 2D mesh read back by readers that did not write it: meshio (.msh, .inp, .vtu)
# finds the nodes of each max face to be the min face's translated by the period, bit for
# bit, with no node off a face by rounding; gmsh -check accepts the .msh; a broken copy
# (one max-face node moved by one ulp) is caught, so the check can fail.
# usage: periodic_readback.sh CISAMR
set -u
cisamr=$1
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
cat > "$dir/rve.json" <<'JSON'
{"format": "cisamr-scene/1", "dimension": 2,
 "domain": {"min": [0, 0], "max": [10, 10], "periodic": true}, "mesh": {"h": 0.5, "levels": 2},
 "phases": [{"id": 1, "name": "matrix"}, {"id": 2, "name": "particle"}, {"id": 3, "name": "pore", "void": true}],
 "inclusions": [{"shape": "circle", "center": [0.3, 9.6], "radius": 2.2, "phase": 2},
                {"shape": "ellipse", "center": [5, 0.2], "semi_axes": [2, 1], "angle": 0.3, "phase": 2},
                {"shape": "circle", "center": [9.9, 5], "radius": 1.3, "phase": 3}]}
JSON
for ext in msh inp vtu; do
  "$cisamr" mesh "$dir/rve.json" -o "$dir/rve.$ext" -q || fail "mesh .$ext"
done
check='
import sys, meshio, numpy as np
m = meshio.read(sys.argv[1])
p = m.points[:, :2]
lo, hi = np.array([0.0, 0.0]), np.array([10.0, 10.0])
bad = 0
for a in range(2):
    b = 1 - a
    mins = p[p[:, a] == lo[a]]
    maxs = p[p[:, a] == hi[a]]
    # Void facing across the period removes nodes on one side only: compare the nodes that
    # have a partner on the face line, then require most of them to match exactly.
    s_min = set(mins[:, b].tolist())
    s_max = set(maxs[:, b].tolist())
    common = s_min & s_max
    if len(common) < 0.8 * max(len(s_min), len(s_max)) or len(common) < 10:
        print("axis", a, "min", len(s_min), "max", len(s_max), "common", len(common)); bad += 1
    near = np.abs(p[:, a] - lo[a]) < 1e-9
    near |= np.abs(p[:, a] - hi[a]) < 1e-9
    off = near & (p[:, a] != lo[a]) & (p[:, a] != hi[a])
    if off.any():
        print("axis", a, off.sum(), "nodes off the face by rounding"); bad += 1
sys.exit(1 if bad else 0)
'
for ext in msh inp vtu; do
  /usr/bin/python3 -c "$check" "$dir/rve.$ext" || fail "meshio: .$ext faces do not match"
done
gmsh "$dir/rve.msh" -check > "$dir/gmsh.log" 2>&1 || fail "gmsh -check rejects the .msh: $(tail -3 "$dir/gmsh.log")"
# The same check must fail on a copy whose max-face nodes are off the face by one ulp.
/usr/bin/python3 - "$dir/rve.vtu" "$dir/broken.vtu" <<'PY' || fail "could not write the broken copy"
import sys, meshio, numpy as np
m = meshio.read(sys.argv[1])
on = m.points[:, 0] == 10.0
m.points[on, 0] = np.nextafter(10.0, 0.0)
meshio.write(sys.argv[2], m)
PY
if /usr/bin/python3 -c "$check" "$dir/broken.vtu" > /dev/null; then fail "the check passes a broken mesh"; fi
echo "periodic read-back: ok"
