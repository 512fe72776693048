#!/bin/bash
# certify reads cohesive meshes back and checks them (issue #13, docs/cohesive-design.md
# §6): the .vtu, .msh and .inp that `cisamr mesh --cohesive` writes for a 2D and a 3D
# example and for a periodic square with cells on a periodic plane pass, with a cohesive
# report in the summary and the JSON; each format edited to
# drop a cohesive cell, to move a top node off its bottom, or to swap a cell's bottom and
# top fails with exit 3 and the matching count. `--explode F` writes a .vtu whose regions
# are moved apart (every cohesive cell open, each region shifted as one piece) and is
# refused with exit 2, before meshing, without --cohesive or a .vtu. With MPIEXEC: the .pvtu
# of 2 ranks passes certify, and --gather --explode writes the sequential run's exploded file.
# usage: cohesive_certify.sh CISAMR SOURCE_DIR [MPIEXEC]
set -u
cisamr=$1 source_dir=$2 mpiexec=${3:-}
. "$(dirname "$0")/common.sh"

# Edits one cohesive cell of a file: drop it, move its first top node by 1e-7 in x, or
# swap its bottom and top nodes (in every format the file order holds the bottom's nodes
# first, then the top's). usage: edit.py FORMAT EDIT IN OUT
cat > "$dir/edit.py" <<'EOF'
import sys
fmt, edit, src, out = sys.argv[1:5]

def edited_nodes(nodes, dim):
    return nodes[dim:] + nodes[:dim] if edit == "swap" else nodes

if fmt == "vtu":
    import meshio
    m = meshio.read(src)
    k = next(i for i, b in enumerate(m.cells) if b.type in ("quad", "wedge"))
    dim = 2 if m.cells[k].type == "quad" else 3
    data = m.cells[k].data
    if edit == "drop":
        m.cells[k] = meshio.CellBlock(m.cells[k].type, data[1:])
        for name in m.cell_data:
            m.cell_data[name][k] = m.cell_data[name][k][1:]
    elif edit == "move":
        m.points[data[0][dim], 0] += 1e-7
    else:
        data[0] = list(edited_nodes(list(data[0]), dim))
    meshio.write(out, m)
    sys.exit(0)

lines = open(src).read().split("\n")
if fmt == "inp":
    first = next(i for i, l in enumerate(lines) if l.startswith("*ELEMENT, TYPE=COH")) + 1
    fields = [f.strip() for f in lines[first].split(",")]
    dim = (len(fields) - 1) // 2
    if edit == "drop":
        del lines[first]
    elif edit == "swap":
        lines[first] = ", ".join([fields[0]] + edited_nodes(fields[1:], dim))
    else:
        at = next(i for i, l in enumerate(lines) if l.startswith(fields[1 + dim] + ","))
        x = [f.strip() for f in lines[at].split(",")]
        lines[at] = ", ".join([x[0], repr(float(x[1]) + 1e-7)] + x[2:])
elif fmt == "msh":
    start = lines.index("$Elements")
    header = start + 2
    while True:  # the element blocks: dim, entity, type, count
        dim_, entity, kind, count = map(int, lines[header].split())
        if kind in (3, 6):
            break
        header += count + 1
    first = header + 1
    fields = lines[first].split()
    dim = (len(fields) - 1) // 2
    if edit == "drop":
        del lines[first]
        lines[header] = "%d %d %d %d" % (dim_, entity, kind, count - 1)
        total = lines[start + 1].split()
        total[1] = str(int(total[1]) - 1)
        lines[start + 1] = " ".join(total)
    elif edit == "swap":
        lines[first] = " ".join([fields[0]] + edited_nodes(fields[1:], dim))
    else:  # our $Nodes: one block, the tags 1..n, then one line of coordinates per node
        nodes = lines.index("$Nodes")
        n = int(lines[nodes + 1].split()[1])
        at = nodes + 3 + n + int(fields[1 + dim]) - 1
        x = lines[at].split()
        lines[at] = " ".join([repr(float(x[0]) + 1e-7)] + x[1:])
open(out, "w").write("\n".join(lines))
EOF

# The value of a key of the certificate's cohesive object.
json_count() { /usr/bin/python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["cohesive"][sys.argv[2]])' "$1" "$2"; }

have_meshio=1
/usr/bin/python3 -c 'import meshio' 2>/dev/null || have_meshio=0

# A periodic square whose box inclusion lies on the x planes: cohesive cells on a periodic
# plane, checked in the frame the file's constraints give (certify without --scene).
cat > "$dir/plane.json" <<'EOF'
{"format": "cisamr-scene/1", "dimension": 2, "domain": {"min": [0, 0], "max": [8, 8], "periodic": true},
 "mesh": {"h": 1.0}, "phases": [{"id": 1, "name": "matrix"}, {"id": 2, "name": "box"}],
 "inclusions": [{"shape": "polygon", "vertices": [[0, 2], [3, 2], [3, 5], [0, 5]], "closed": true, "phase": 2}]}
EOF

for scene in composite spheres3d plane; do
  scene_file="$source_dir/data/examples/$scene.json"
  [ "$scene" = plane ] && scene_file="$dir/plane.json"
  for ext in vtu msh inp; do
    mesh="$dir/$scene.$ext"
    "$cisamr" mesh "$scene_file" -o "$mesh" --cohesive -q || fail "mesh $scene.$ext"
    if [ "$scene" = plane ]; then
      "$cisamr" certify "$mesh" --scene "$scene_file" -q || fail "certify $scene.$ext against its scene"
    fi
    "$cisamr" certify "$mesh" --json "$dir/c.json" > "$dir/summary.txt"
    rc=$?
    [ $rc -eq 0 ] || fail "certify $scene.$ext: exit $rc: $(cat "$dir/summary.txt")"
    grep -Eq '^cohesive: [1-9][0-9]* elements in [0-9]+ (sets?|phase pairs?); every interface facet covered once$' "$dir/summary.txt" ||
      fail "$scene.$ext: no cohesive line in the summary: $(cat "$dir/summary.txt")"
    [ "$(json_count "$dir/c.json" ok)" = True ] || fail "$scene.$ext: the JSON's cohesive object is not ok"
    [ "$(json_count "$dir/c.json" elements)" = "$(json_count "$dir/c.json" interface_facets)" ] ||
      fail "$scene.$ext: cohesive elements and interface facets differ"
    if [ "$ext" != vtu ]; then
      [ "$(json_count "$dir/c.json" sets_named)" = True ] || fail "$scene.$ext: the sets were not checked"
    fi
    # drop: an interface facet left uncovered; move: a top off its bottom; swap: the
    # bottom on the upper phase's nodes.
    for edit in drop:uncovered move:not_coincident swap:wrong_sides; do
      [ "$ext" = vtu ] && [ $have_meshio -eq 0 ] && continue
      broken="$dir/broken_${edit%%:*}.$ext"
      /usr/bin/python3 "$dir/edit.py" "$ext" "${edit%%:*}" "$mesh" "$broken" || fail "cannot edit $scene.$ext (${edit%%:*})"
      "$cisamr" certify "$broken" --json "$dir/b.json" -q
      rc=$?
      [ $rc -eq 3 ] || fail "certify $scene.$ext with ${edit%%:*}: exit $rc, expected 3"
      count=$(json_count "$dir/b.json" "${edit#*:}")
      [ "$count" -ge 1 ] 2>/dev/null || fail "$scene.$ext with ${edit%%:*}: ${edit#*:} is '$count'"
    done
  done
  echo "$scene: .vtu, .msh and .inp certified; every edited copy fails"
  [ "$scene" = plane ] && continue

  # --explode: every cohesive cell opens (no top on its bottom), and each bulk region moves
  # as one piece, regions by different amounts.
  exploded="$dir/${scene}_exploded.vtu"
  "$cisamr" mesh "$source_dir/data/examples/$scene.json" -o "$exploded" --cohesive --explode 1.5 -q || fail "mesh --explode $scene"
  "$cisamr" certify "$exploded" --json "$dir/e_$scene.json" -q
  [ $? -eq 3 ] || fail "$scene: an exploded mesh must fail certify"
  [ "$(json_count "$dir/e_$scene.json" not_coincident)" = "$(json_count "$dir/e_$scene.json" elements)" ] ||
    fail "$scene: not every cohesive cell of the exploded mesh is open"
  if [ $have_meshio -eq 1 ]; then
    /usr/bin/python3 - "$dir/$scene.vtu" "$exploded" <<'EOF' || fail "$scene: the exploded regions did not move as pieces"
import sys, meshio, numpy as np
a, b = meshio.read(sys.argv[1]), meshio.read(sys.argv[2])
shift = b.points - a.points
bulk = [blk.data for blk in a.cells if blk.type in ("triangle", "tetra")]
bulk = [blk for blk in bulk if blk.shape[1] == (4 if any(x.type == "tetra" for x in a.cells) else 3)]
parent = list(range(len(a.points)))
def root(n):
    while parent[n] != n:
        parent[n] = parent[parent[n]]
        n = parent[n]
    return n
for cells in bulk:
    for cell in cells:
        r = root(int(cell[0]))
        for n in cell[1:]:
            s = root(int(n))
            if s != r:
                parent[s] = r
used = np.unique(np.concatenate([c.ravel() for c in bulk]))
regions = {}
for n in used:
    regions.setdefault(root(int(n)), []).append(n)
moves = [shift[ids].mean(axis=0) for ids in regions.values()]
for ids, move in zip(regions.values(), moves):
    assert np.abs(shift[ids] - move).max() < 1e-12, "a region does not move as one piece"
assert len(regions) > 1, "one region only"
distinct = {tuple(np.round(m, 12)) for m in moves}
assert len(distinct) == len(regions), "two regions moved alike"
print("%d regions moved apart" % len(regions))
EOF
  fi
done

if [ -n "$mpiexec" ]; then
  scene="$source_dir/data/examples/spheres3d.json"
  timeout 120 "$mpiexec" -n 2 --oversubscribe --allow-run-as-root "$cisamr" mesh "$scene" -o "$dir/p.pvtu" --cohesive -q ||
    fail "mpiexec: mesh .pvtu"
  "$cisamr" certify "$dir/p.pvtu" > "$dir/summary.txt" || fail "certify the .pvtu of 2 ranks: $(cat "$dir/summary.txt")"
  grep -q '^cohesive: .*every interface facet covered once$' "$dir/summary.txt" || fail "the .pvtu: no cohesive line"
  timeout 120 "$mpiexec" -n 2 --oversubscribe --allow-run-as-root "$cisamr" mesh "$scene" -o "$dir/g.vtu" --gather \
    --cohesive --explode 1.5 -q || fail "mpiexec: mesh --gather --explode"
  "$cisamr" certify "$dir/g.vtu" --json "$dir/g.json" -q
  [ "$(json_count "$dir/g.json" not_coincident)" = "$(json_count "$dir/e_spheres3d.json" elements)" ] ||
    fail "the gathered exploded mesh differs from the sequential one in its open cohesive cells"
  echo "mpiexec: the .pvtu of 2 ranks certified; --gather --explode opens every cohesive cell"
fi

# Refusals: before meshing (no output), exit 2, one line.
scene="$source_dir/data/examples/composite.json"
for args in "-o $dir/r.vtu --explode 2" "-o $dir/r.msh --cohesive --explode 2" "-o $dir/r.vtu --cohesive --explode 1"; do
  # shellcheck disable=SC2086
  "$cisamr" mesh "$scene" $args -q 2> "$dir/err.txt"
  rc=$?
  [ $rc -eq 2 ] || fail "mesh $args: exit $rc, expected 2"
  [ "$(wc -l < "$dir/err.txt")" -eq 1 ] || fail "mesh $args: not one line: $(cat "$dir/err.txt")"
  grep -q -- "--explode" "$dir/err.txt" || fail "mesh $args: the error does not name --explode: $(cat "$dir/err.txt")"
  ls "$dir"/r.* > /dev/null 2>&1 && fail "mesh $args left an output"
done
echo "cohesive certify: ok"
