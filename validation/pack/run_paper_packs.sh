#!/usr/bin/env bash
# Packs the paper's four microstructures (data/paper/*.json) with `cisamr pack`, timing each
# with /usr/bin/time, then partitions E1 into N = 20, 40, 100 boxes next to a uniform grid.
# Usage: validation/pack/run_paper_packs.sh [BUILD_DIR] [OUT_DIR]   (Release build expected)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
build="${1:-$root/build}"
out="${2:-$(mktemp -d)}"
cisamr="$build/bin/cisamr"
mkdir -p "$out"
[ -x "$cisamr" ] || { echo "no $cisamr: build the 'cisamr' target first" >&2; exit 1; }

for spec in "$root"/data/paper/e*.json; do
  name="$(basename "$spec" .json)"
  echo "== $name"
  /usr/bin/time -f "   wall %e s, peak memory %M KiB" "$cisamr" pack "$spec" -o "$out/$name.scene.json"
done

echo "== E1 partitions (Algorithm 1 as implemented vs. merging only vs. a uniform grid)"
for n in 20 40 100; do
  for method in best merge; do
    /usr/bin/time -f "   wall %e s" "$cisamr" partition "$out/e1_sic_particles.scene.json" -n "$n" --method "$method" \
      -o "$out/e1_parts_${n}_${method}.json" --svg "$out/e1_parts_${n}_${method}.svg" \
      $([ "$method" = best ] && echo --compare-uniform)
  done
done
echo "outputs in $out"
