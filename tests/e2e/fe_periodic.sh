#!/bin/bash
# CalculiX through the periodic constraints of a cisamr .inp (validation/fe/homogenise.py):
#  - smoke: the smallest periodic mesh (2 × 2 cells, no inclusion): ccx accepts the REF
#    nodes, which belong to no element, and the unit strains come out uniform;
#  - a periodic RVE of ONE material (plane strain CPE3, inclusions crossing every face and
#    a corner): CORNER0 fixed, REF_X / REF_Y prescribed for each unit strain (xx, yy, xy
#    shear): every element's strain equals the imposed one to 1e-6 relative, and the
#    effective stiffness equals the material's (to ccx's 7 printed digits);
#  - two materials: symmetric, and between the Reuss and Voigt bounds in the Loewner order;
#  - the same on a small 3D periodic RVE (six unit strains, C3D4);
#  - a mesh periodic along x only is refused (exit 2, one line), and ccx is never run.
# Exit 77 (skipped) only when ccx is missing.
# usage: fe_periodic.sh CISAMR SOURCE_DIR
set -u
cisamr=$1 source_dir=$2
hom=$source_dir/validation/fe/homogenise.py
command -v ccx > /dev/null || { echo "ccx (CalculiX) not found: skipped"; exit 77; }
. "$(dirname "$0")/common.sh"
# check JSON EXPRESSION MESSAGE: the expression, over the result r, must hold.
check() {
  /usr/bin/python3 -c 'import json, sys
r = json.load(open(sys.argv[1]))
C, V, R = r["stiffness"], r["voigt"], r["reuss"]
scale = max(abs(x) for row in C for x in row)
ok = eval(sys.argv[2])
print(("ok  " if ok else "FAIL") + " " + sys.argv[3] + ": strain deviation %.2e, C11 %.7g C22 %.7g C12 %.7g C33 %.7g (Voigt C11 %.7g, Reuss C11 %.7g)"
      % (r["max_strain_deviation"], C[0][0], C[1][1], C[0][1], C[2][2], V[0][0], R[0][0]))
sys.exit(0 if ok else 1)' "$1" "$2" "$3" || fail "$3"
}

cat > "$dir/square.json" <<'JSON'
{"format": "cisamr-scene/1", "dimension": 2,
 "domain": {"min": [0, 0], "max": [10, 10], "periodic": true}, "mesh": {"h": 5},
 "phases": [{"id": 1, "name": "matrix"}], "inclusions": []}
JSON
cat > "$dir/rve.json" <<'JSON'
{"format": "cisamr-scene/1", "dimension": 2,
 "domain": {"min": [0, 0], "max": [10, 10], "periodic": true}, "mesh": {"h": 0.5, "levels": 2},
 "phases": [{"id": 1, "name": "matrix"}, {"id": 2, "name": "particle"}],
 "inclusions": [{"shape": "circle", "center": [0.3, 9.6], "radius": 2.2, "phase": 2},
                {"shape": "ellipse", "center": [5, 0.2], "semi_axes": [2, 1], "angle": 0.3, "phase": 2},
                {"shape": "circle", "center": [9.9, 5], "radius": 1.3, "phase": 2}]}
JSON
sed 's/"periodic": true/"periodic": [true, false]/' "$dir/rve.json" > "$dir/x_only.json"
"$cisamr" mesh "$dir/square.json" -o "$dir/square.inp" --plane strain -q || fail "mesh the square"
"$cisamr" mesh "$dir/rve.json" -o "$dir/rve.inp" --plane strain -q || fail "mesh the RVE"
"$cisamr" mesh "$dir/x_only.json" -o "$dir/x_only.inp" --plane strain -q || fail "mesh the x-periodic RVE"

# Plane strain, E 1000, nu 0.3: C11 = E(1-nu)/((1+nu)(1-2nu)), C12 = E nu/((1+nu)(1-2nu)), C33 = E/(2(1+nu)).
exact='abs(C[0][0] - 1346.153846) <= 1e-6 * scale and abs(C[1][1] - 1346.153846) <= 1e-6 * scale and abs(C[0][1] - 576.9230769) <= 1e-6 * scale and abs(C[2][2] - 384.6153846) <= 1e-6 * scale and abs(C[0][2]) + abs(C[1][2]) <= 1e-6 * scale'
uniform="r['max_strain_deviation'] <= 1e-6 and r['element_type'] == 'CPE3' and $exact"
/usr/bin/python3 "$hom" "$dir/square.inp" --material matrix=1000,0.3 --json "$dir/r.json" > /dev/null || fail "smoke: ccx on the 2 x 2 periodic square"
check "$dir/r.json" "$uniform and r['elements'] == 8 and r['slaves'] == 5" "smoke, 8 triangles, REF nodes in no element"
/usr/bin/python3 "$hom" "$dir/rve.inp" --material matrix=1000,0.3 --material particle=1000,0.3 --json "$dir/r.json" > /dev/null || fail "one material: run"
check "$dir/r.json" "$uniform" "RVE, one material: uniform strain in every element"

bounded='r["asymmetry"] <= 1e-6 and r["min_eig_above_reuss"] >= -1e-6 * scale and r["min_eig_below_voigt"] >= -1e-6 * scale and R[0][0] * 1.01 < C[0][0] < V[0][0] * 0.99'
/usr/bin/python3 "$hom" "$dir/rve.inp" --material matrix=1000,0.3 --material particle=20000,0.2 --json "$dir/r.json" > /dev/null || fail "two materials: run"
check "$dir/r.json" "$bounded" "RVE, two materials: symmetric, between Reuss and Voigt"

# 3D: a small periodic RVE made by the mesher (a sphere across a corner, a fibre through
# two faces): one material gives uniform strain in every tetrahedron under the six unit
# strains and the isotropic stiffness (E 1000, nu 0.3: C11 1346.15, C12 576.92, C44 384.62);
# two materials lie between the bounds.
cat > "$dir/rve3.json" <<'JSON'
{"format": "cisamr-scene/1", "dimension": 3,
 "domain": {"min": [0, 0, 0], "max": [1, 1, 1], "periodic": true}, "mesh": {"h": 0.25, "levels": 1},
 "phases": [{"id": 1, "name": "matrix"}, {"id": 2, "name": "particle"}],
 "inclusions": [{"shape": "sphere", "center": [0.95, 0.05, 0.9], "radius": 0.3, "phase": 2},
                {"shape": "cylinder", "start": [0.5, -0.2, 0.45], "end": [0.5, 1.2, 0.45], "radius": 0.1, "phase": 2}]}
JSON
"$cisamr" mesh "$dir/rve3.json" -o "$dir/rve3.inp" -q || fail "mesh the 3D RVE"
exact3='all(abs(C[i][i] - 1346.153846) <= 1e-6 * scale for i in range(3)) and all(abs(C[i][i] - 384.6153846) <= 1e-6 * scale for i in range(3, 6)) and abs(C[0][1] - 576.9230769) <= 1e-6 * scale'
/usr/bin/python3 "$hom" "$dir/rve3.inp" --material matrix=1000,0.3 --material particle=1000,0.3 --json "$dir/r.json" > /dev/null || fail "3D one material: run"
check "$dir/r.json" "r['max_strain_deviation'] <= 1e-6 and r['element_type'] == 'C3D4' and $exact3" "3D RVE, one material: uniform strain in every tetrahedron"
/usr/bin/python3 "$hom" "$dir/rve3.inp" --material matrix=1000,0.3 --material particle=20000,0.2 --json "$dir/r.json" > /dev/null || fail "3D two materials: run"
check "$dir/r.json" "$bounded" "3D RVE, two materials: symmetric, between Reuss and Voigt"

/usr/bin/python3 "$hom" "$dir/x_only.inp" --material matrix=1000,0.3 --material particle=1000,0.3 > /dev/null 2> "$dir/err.txt"
[ $? -eq 2 ] && grep -q "periodic along every axis" "$dir/err.txt" && [ "$(wc -l < "$dir/err.txt")" -eq 1 ] ||
  fail "a mesh periodic along x only is not refused clearly: $(cat "$dir/err.txt")"
echo "fe periodic: ok"
