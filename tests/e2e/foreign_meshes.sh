#!/bin/bash
# Meshes written by other tools certify against the scene, phases matched by name
# (lib/io/README.md, "Reading meshes"). cisamr meshes a 2D and a 3D scene; Gmsh (MSH 4.1
# binary, 2.2 ASCII and binary), meshio (zlib-compressed, raw and ASCII VTU), VTK (ASCII
# VTU, its default appended compressed VTU, legacy .vtk ASCII and binary, versions 5.1
# and 4.2) and TetGen (.node/.ele, 1- and 0-based, reconstructed with -r) convert them;
# with MPI a .pvtu of pieces too. Each is certified against a copy of the scene whose
# phase ids differ from the files' tags, so only the names can match them; where a tool
# drops the names (meshio's VTU writer, TetGen), matching by number must fail with one line
# and exit 2, and --phase-map must then make it pass.
# usage: foreign_meshes.sh CISAMR [MPIEXEC]
set -u
cisamr=$1 mpiexec=${2:-}
py=/usr/bin/python3  # Debian's python, where meshio and vtk live
. "$(dirname "$0")/common.sh"
cd "$dir" || exit 1
for tool in gmsh tetgen; do
  command -v $tool > /dev/null || fail "$tool is missing (scripts/install-deps.sh installs it)"
done
$py -c 'import meshio, vtk' || fail "python3-meshio or python3-vtk9 is missing (scripts/install-deps.sh)"

cat > s2.json <<'EOF'
{"format": "cisamr-scene/1", "dimension": 2, "domain": {"min": [0, 0], "max": [1, 1]},
 "mesh": {"h": 0.1, "levels": 1}, "phases": [{"id": 1, "name": "matrix"}, {"id": 2, "name": "fiber"}],
 "matrix_phase": 1, "inclusions": [{"shape": "circle", "center": [0.5, 0.5], "radius": 0.25, "phase": 2}]}
EOF
cat > s3.json <<'EOF'
{"format": "cisamr-scene/1", "dimension": 3, "domain": {"min": [0, 0, 0], "max": [1, 1, 1]},
 "mesh": {"h": 0.2, "levels": 1}, "phases": [{"id": 1, "name": "epoxy"}, {"id": 2, "name": "silica"}],
 "matrix_phase": 1, "inclusions": [{"shape": "sphere", "center": [0.5, 0.5, 0.5], "radius": 0.3, "phase": 2}]}
EOF
# The same scenes with phase ids 5 (matrix) and 9 (inclusion): the files keep tags 1 and 2.
for s in s2 s3; do
  $py -c 'import json, sys
scene = json.load(open(sys.argv[1]))
new = {1: 5, 2: 9}
for p in scene["phases"]: p["id"] = new[p["id"]]
scene["matrix_phase"] = 5
for i in scene["inclusions"]: i["phase"] = 9
json.dump(scene, open(sys.argv[2], "w"))' $s.json ${s}r.json
done
names2="'matrix' -> 5, 'fiber' -> 9"
names3="'epoxy' -> 5, 'silica' -> 9"

# certify FILE SCENE EXPECTED_NOTE [OPTIONS...]: exit 0, the phases matched as expected, and
# the certificate's per-phase cells under the scene's ids.
passes() {
  local file=$1 scene=$2 note=$3
  shift 3
  "$cisamr" certify "$file" --scene "$scene" --json cert.json "$@" > out.txt 2> err.txt
  local rc=$?
  [ $rc -eq 0 ] || { cat out.txt err.txt; fail "$file: certify exit $rc, expected 0"; }
  grep -qF "mesh phases matched to the scene: $note" out.txt || { cat out.txt; fail "$file: phases not matched as $note"; }
  $py -c 'import json, sys
c = json.load(open(sys.argv[1]))
ids = sorted(p["phase"] for p in c["cells_per_phase"])
assert ids == [5, 9] and c["passed"], ids' cert.json || fail "$file: the certificate's phases are not the scene's 5 and 9"
}
# A mesh without names against the renumbered scene: a one-line error naming the file, exit 2.
refused_by_number() {
  local file=$1 scene=$2
  "$cisamr" certify "$file" --scene "$scene" > out.txt 2> err.txt
  local rc=$?
  [ $rc -eq 2 ] || { cat out.txt err.txt; fail "$file: exit $rc without names or --phase-map, expected 2"; }
  [ "$(wc -l < err.txt)" -eq 1 ] && grep -q "$file: phase: mesh phase 1 is not a phase of the scene" err.txt \
    || { cat err.txt; fail "$file: expected one line saying mesh phase 1 is not in the scene"; }
}

for s in s2 s3; do
  "$cisamr" mesh $s.json -o $s.msh -q || fail "mesh $s.msh"
  "$cisamr" mesh $s.json -o $s.vtu -q || fail "mesh $s.vtu"
  "$cisamr" mesh $s.json -o $s.mesh -q || fail "mesh $s.mesh"
  if [ $s = s2 ]; then names=$names2 map="1=matrix,2=fiber"; else names=$names3 map="1=epoxy,2=silica"; fi

  # --- Gmsh: MSH 4.1 binary, 2.2 ASCII and binary; physical names kept. ---------------------
  gmsh $s.msh -save -format msh41 -bin -o $s.gmsh41b.msh > gmsh.log 2>&1 || { cat gmsh.log; fail "gmsh msh41 -bin"; }
  gmsh $s.msh -save -format msh22 -o $s.gmsh22.msh > gmsh.log 2>&1 || { cat gmsh.log; fail "gmsh msh22"; }
  gmsh $s.msh -save -format msh22 -bin -o $s.gmsh22b.msh > gmsh.log 2>&1 || { cat gmsh.log; fail "gmsh msh22 -bin"; }
  head -2 $s.gmsh41b.msh | grep -q "^4.1 1 8" || fail "gmsh did not write binary MSH 4.1"
  head -2 $s.gmsh22b.msh | grep -q "^2.2 1 8" || fail "gmsh did not write binary MSH 2.2"
  for f in gmsh41b gmsh22 gmsh22b; do passes $s.$f.msh ${s}r.json "$names"; done

  # --- meshio (reading our MSH): compressed VTU (its default), raw and ASCII VTU. -----------
  # meshio's VTU writer drops the physical names (no FieldData): by number it must fail.
  $py -c 'import meshio, sys
m = meshio.read(sys.argv[1])
meshio.write(sys.argv[2], m)  # binary, compression="zlib"
meshio.write(sys.argv[3], m, compression=None)
meshio.write(sys.argv[4], m, binary=False)' $s.msh $s.meshio_zlib.vtu $s.meshio_raw.vtu $s.meshio_ascii.vtu 2> meshio.log \
    || { cat meshio.log; fail "meshio"; }
  grep -q 'compressor="vtkZLibDataCompressor"' $s.meshio_zlib.vtu || fail "meshio did not compress"
  for f in meshio_zlib meshio_raw meshio_ascii; do
    refused_by_number $s.$f.vtu ${s}r.json
    passes $s.$f.vtu ${s}r.json "1 -> 5, 2 -> 9" --phase-map "$map"
  done

  # --- VTK (reading our VTU): ASCII VTU, its default VTU (appended, zlib), legacy .vtk. ------
  # The names go in as field data phase_names/phase_ids (added from the scene when our
  # VTU does not carry them) and VTK's writers must keep them.
  $py -c 'import json, sys, vtk
src, scene, xml_ascii, xml_default, legacy_ascii, legacy_binary, legacy_42 = sys.argv[1:8]
reader = vtk.vtkXMLUnstructuredGridReader(); reader.SetFileName(src); reader.Update()
grid = reader.GetOutput()
field = grid.GetFieldData()
if field.GetAbstractArray("phase_names") is None:
    names = vtk.vtkStringArray(); names.SetName("phase_names")
    ids = vtk.vtkIntArray(); ids.SetName("phase_ids")
    for p in json.load(open(scene))["phases"]:
        names.InsertNextValue(p["name"]); ids.InsertNextValue(p["id"])
    field.AddArray(names); field.AddArray(ids)
def xml(path, ascii):
    w = vtk.vtkXMLUnstructuredGridWriter(); w.SetFileName(path); w.SetInputData(grid)
    if ascii: w.SetDataModeToAscii()
    assert w.Write() == 1
def legacy(path, binary, version=None):
    w = vtk.vtkUnstructuredGridWriter(); w.SetFileName(path); w.SetInputData(grid)
    w.SetFileTypeToBinary() if binary else w.SetFileTypeToASCII()
    if version: w.SetFileVersion(version)
    assert w.Write() == 1
xml(xml_ascii, True); xml(xml_default, False)
legacy(legacy_ascii, False); legacy(legacy_binary, True); legacy(legacy_42, True, 42)' \
    $s.vtu $s.json $s.vtk_ascii.vtu $s.vtk_default.vtu $s.legacy_ascii.vtk $s.legacy_binary.vtk $s.legacy42.vtk \
    2> vtk.log || { cat vtk.log; fail "vtk"; }
  grep -q 'format="ascii"' $s.vtk_ascii.vtu || fail "VTK did not write ASCII"
  grep -q 'compressor="vtkZLibDataCompressor"' $s.vtk_default.vtu || fail "VTK's default VTU is not compressed"
  head -3 $s.legacy_binary.vtk | grep -q BINARY || fail "VTK did not write a binary legacy file"
  head -1 $s.legacy42.vtk | grep -q "Version 4.2" || fail "VTK did not write legacy version 4.2"
  for f in vtk_ascii.vtu vtk_default.vtu legacy_ascii.vtk legacy_binary.vtk legacy42.vtk; do
    passes $s.$f ${s}r.json "$names"
  done
done

# --- TetGen: the same tetrahedra reconstructed (-r) from our Medit file, written as
# .node/.ele with the Medit reference as region attribute; 1-based and 0-based (-z). --------
mkdir one zero
cp s3.mesh one/ && cp s3.mesh zero/
(cd one && tetgen -r s3.mesh > tetgen.log 2>&1) || fail "tetgen -r"
(cd zero && tetgen -rz s3.mesh > tetgen.log 2>&1) || fail "tetgen -rz"
read -r first_one < <(sed -n 2p one/s3.1.node)
read -r first_zero < <(sed -n 2p zero/s3.1.node)
[ "${first_one%% *}" = 1 ] && [ "${first_zero%% *}" = 0 ] || fail "tetgen -z did not number from 0"
for f in one/s3.1.ele zero/s3.1.node; do
  refused_by_number $f s3r.json
  passes $f s3r.json "1 -> 5, 2 -> 9" --phase-map "1=epoxy,2=silica"
  passes $f s3r.json "1 -> 5, 2 -> 9" --phase-map "1=5,2=9"
done
# TetGen reconstructed our tetrahedra: the same node and cell counts as our own file.
"$cisamr" certify s3.mesh --scene s3.json > ours.txt || fail "our own s3.mesh"
"$cisamr" certify one/s3.1.ele --scene s3.json > theirs.txt || fail "TetGen's s3.1.ele by number"
[ "$(grep '^mesh:' ours.txt | cut -d: -f3)" = "$(grep '^mesh:' theirs.txt | cut -d: -f3)" ] \
  || fail "TetGen's mesh differs in size: $(grep '^mesh:' ours.txt theirs.txt)"

# --- .pvtu pieces from a parallel run (nodes merged by global_id). ------------------------
if [ -n "$mpiexec" ]; then
  timeout 120 "$mpiexec" -n 2 --oversubscribe --allow-run-as-root "$cisamr" mesh s3.json -o p.pvtu -q \
    || fail "parallel mesh to p.pvtu"
  passes p.pvtu s3r.json "'epoxy' -> 5, 'silica' -> 9"  # the pieces carry the names
  [ "$(grep '^mesh:' out.txt | cut -d: -f3)" = "$(grep '^mesh:' ours.txt | cut -d: -f3)" ] \
    || fail "p.pvtu: the pieces' shared nodes were not merged: $(grep '^mesh:' out.txt ours.txt)"
fi
# --- A mesh with a void certifies without a scene (its hole is taken for a void). ---------
cat > void.json <<'EOF'
{"format": "cisamr-scene/1", "dimension": 2, "domain": {"min": [0, 0], "max": [1, 1]},
 "mesh": {"h": 0.1, "levels": 1}, "phases": [{"id": 1, "name": "matrix"}, {"id": 2, "name": "pore", "void": true}],
 "matrix_phase": 1, "inclusions": [{"shape": "circle", "center": [0.5, 0.5], "radius": 0.25, "phase": 2}]}
EOF
"$cisamr" mesh void.json -o void.msh -q || fail "mesh void.msh"
"$cisamr" certify void.msh --json void.cert.json > out.txt 2>&1 || { cat out.txt; fail "a mesh with a void does not certify without a scene"; }
$py -c 'import json, sys
c = json.load(open(sys.argv[1]))["conformity"]
assert c["inner_boundary_facets"] > 0 and c["open_facets_inside"] == 0, c' void.cert.json \
  || fail "the void's boundary was not counted as inner boundary"
echo "foreign meshes: all certified"
