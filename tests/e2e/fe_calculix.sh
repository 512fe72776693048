#!/bin/bash
# CalculiX solves on cisamr meshes through their boundary sets (validation/fe/cisamr_fe.py):
# with one material everywhere the strain is the same in every element (to 1e-6) and the
# apparent modulus is E (3D, 2D plane stress) or E/(1-nu^2) (2D plane strain), for both
# support variants; with two materials of equal nu it lies between the Reuss and Voigt
# bounds of the mesh's phase volumes. Exit 77 (skipped) only when ccx is missing.
# usage: fe_calculix.sh CISAMR SOURCE_DIR
set -u
cisamr=$1 source_dir=$2
fe=$source_dir/validation/fe/cisamr_fe.py
command -v ccx > /dev/null || { echo "ccx (CalculiX) not found: skipped"; exit 77; }
. "$(dirname "$0")/common.sh"
# check JSON EXPRESSION MESSAGE: the expression, over the result r, must hold.
check() {
  /usr/bin/python3 -c 'import json, sys
r = json.load(open(sys.argv[1]))
ok = eval(sys.argv[2])
print(("ok  " if ok else "FAIL") + " " + sys.argv[3] + ": E %.10g (Voigt %.10g, Reuss %.10g), strain deviation %.2e"
      % (r["apparent_modulus"], r["voigt"], r["reuss"], r["strains"]["max_deviation_over_exx"]))
sys.exit(0 if ok else 1)' "$1" "$2" "$3" || fail "$3"
}

cat > "$dir/s3.json" <<'JSON'
{"format": "cisamr-scene/1", "dimension": 3,
 "domain": {"min": [0, 0, 0], "max": [0.3, 0.2, 0.2]}, "mesh": {"h": 0.05, "levels": 1},
 "phases": [{"id": 1, "name": "matrix"}, {"id": 2, "name": "glass"}],
 "inclusions": [{"shape": "sphere", "center": [0.15, 0.1, 0.1], "radius": 0.06, "phase": 2},
                {"shape": "sphere", "center": [0.3, 0.0, 0.2], "radius": 0.05, "phase": 2}]}
JSON
cat > "$dir/s2.json" <<'JSON'
{"format": "cisamr-scene/1", "dimension": 2,
 "domain": {"min": [0.1, -0.7], "max": [0.9, 0.0]}, "mesh": {"h": 0.1, "levels": 1},
 "phases": [{"id": 1, "name": "matrix"}, {"id": 2, "name": "glass fibre"}],
 "inclusions": [{"shape": "circle", "center": [0.5, -0.35], "radius": 0.17, "phase": 2},
                {"shape": "circle", "center": [0.1, 0.0], "radius": 0.12, "phase": 2}]}
JSON
"$cisamr" mesh "$dir/s3.json" -o "$dir/m3.inp" -q || fail "mesh 3D"
"$cisamr" mesh "$dir/s2.json" -o "$dir/stress.inp" -q || fail "mesh 2D"
"$cisamr" mesh "$dir/s2.json" -o "$dir/strain.inp" --plane strain -q || fail "mesh 2D --plane strain"

uniform='abs(r["apparent_modulus"] - X) <= 1e-6 * X and r["strains"]["max_deviation_over_exx"] <= 1e-6'
one=(--material matrix=1000,0.3 --material 2=1000,0.3)
for support in rollers corner0; do
  /usr/bin/python3 "$fe" uniaxial "$dir/m3.inp" "${one[@]}" --support $support --json "$dir/r.json" > /dev/null || fail "3D $support: run"
  check "$dir/r.json" "${uniform//X/1000}" "3D, one material, $support"
  /usr/bin/python3 "$fe" uniaxial "$dir/stress.inp" "${one[@]}" --support $support --thickness 0.5 --json "$dir/r.json" > /dev/null || fail "2D stress $support: run"
  check "$dir/r.json" "${uniform//X/1000} and r['element_type'] == 'CPS3'" "2D plane stress, one material, $support"
  /usr/bin/python3 "$fe" uniaxial "$dir/strain.inp" "${one[@]}" --support $support --json "$dir/r.json" > /dev/null || fail "2D strain $support: run"
  check "$dir/r.json" "${uniform//X/(1000 / (1 - 0.09))} and r['element_type'] == 'CPE3'" "2D plane strain, one material, $support"
done

two=(--material matrix=1000,0.3 --material 2=20000,0.3)
bounded='r["reuss"] < r["apparent_modulus"] < r["voigt"] and r["reuss"] > 1000'
for mesh in m3 stress strain; do
  /usr/bin/python3 "$fe" uniaxial "$dir/$mesh.inp" "${two[@]}" --json "$dir/r.json" > /dev/null || fail "$mesh two materials: run"
  check "$dir/r.json" "$bounded" "$mesh, two materials: between the bounds"
done

# The element-face surfaces: a pressure on XMAX_FACES, YMAX_FACES (and ZMAX_FACES) comes
# back as p × face area in the reactions of XMIN, YMIN (and ZMIN), which a wrong Abaqus
# face id (S1-S4, S1-S3) would spread over the wrong element faces.
surface_job() {  # MESH SECTION_DATA_LINE DIM
  echo "*INCLUDE, INPUT=$1"
  echo "*MATERIAL, NAME=M1"; echo "*ELASTIC"; echo "1000, 0.3"
  for set in $(sed -n 's/^\*ELEMENT.*ELSET=\(.*\)$/\1/p' "$dir/$1"); do
    echo "*SOLID SECTION, ELSET=$set, MATERIAL=M1"; [ -z "$2" ] || echo "$2"
  done
  echo "*STEP"; echo "*STATIC"; echo "*BOUNDARY"; echo "XMIN, 1, 1, 0"; echo "YMIN, 2, 2, 0"
  [ "$3" = 3 ] && echo "ZMIN, 3, 3, 0"
  echo "*DLOAD"; echo "XMAX_FACES, P, -2.0"; echo "YMAX_FACES, P, -3.0"
  [ "$3" = 3 ] && echo "ZMAX_FACES, P, -5.0"
  for set in XMIN YMIN ZMIN; do [ $set = ZMIN ] && [ "$3" = 2 ] && continue; echo "*NODE PRINT, NSET=$set, TOTALS=ONLY"; echo "RF"; done
  echo "*END STEP"
}
# reactions JOB.dat EXPECTED...: the total force component k of the k-th set printed.
reactions() {
  /usr/bin/python3 -c 'import re, sys
text = open(sys.argv[1]).read()
totals = [list(map(float, m.group(1).split()))
          for m in re.finditer(r"total force \(fx,fy,fz\) for set \S+ and time.*\n\s*\n(.*)\n", text)]
want = [float(x) for x in sys.argv[2:]]
got = [totals[k][k] for k in range(len(want))] if len(totals) == len(want) else []
ok = len(got) == len(want) and all(abs(g - w) <= 1e-9 * abs(w) for g, w in zip(got, want))
print(("ok  " if ok else "FAIL") + " face surfaces: reactions", got, "expected", want)
sys.exit(0 if ok else 1)' "$@"
}
surface_job m3.inp "" 3 > "$dir/p3.inp"
(cd "$dir" && OMP_NUM_THREADS=1 ccx -i p3 > p3.log 2>&1) && ! grep -q "ERROR" "$dir/p3.log" || fail "3D surface job"
reactions "$dir/p3.dat" -0.08 -0.18 -0.3 || fail "3D element-face surfaces"   # p × 0.2·0.2, 0.3·0.2, 0.3·0.2
surface_job stress.inp 0.5 2 > "$dir/p2.inp"
(cd "$dir" && OMP_NUM_THREADS=1 ccx -i p2 > p2.log 2>&1) && ! grep -q "ERROR" "$dir/p2.log" || fail "2D surface job"
reactions "$dir/p2.dat" -0.7 -1.2 || fail "2D element-face surfaces"   # p × 0.7·0.5, 0.8·0.5

# Bad input: one line, exit 2.
/usr/bin/python3 "$fe" uniaxial "$dir/m3.inp" --material matrix=1000,0.3 > /dev/null 2> "$dir/err.txt"
[ $? -eq 2 ] && grep -q "no material given" "$dir/err.txt" || fail "a phase without a material is not a clear error"
echo "fe: ok"
