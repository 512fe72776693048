#!/usr/bin/env bash
# Long fuzzing runs with libFuzzer (clang, AddressSanitizer, UndefinedBehaviorSanitizer).
# Configures a separate build directory, builds the fuzz targets as libFuzzer binaries and
# runs each for a time or a number of executions. New interesting inputs go to
# BUILD/fuzz-corpus/TARGET (the seeds in tests/fuzz/corpus stay untouched); crashes, leaks,
# timeouts and out-of-memory inputs go to BUILD/fuzz-artifacts/TARGET/.
#
#   tests/fuzz/run_libfuzzer.sh [-t SECONDS_PER_TARGET | -r RUNS_PER_TARGET] [TARGET...]
#
# Environment: CXX (default clang++-14, or clang++), BUILD (default build-libfuzzer),
# JOBS (build parallelism, default 2). Run from the repository root.
set -euo pipefail

seconds=60
runs=""
while getopts "t:r:" option; do
  case $option in
    t) seconds=$OPTARG ;;
    r) runs=$OPTARG ;;
    *) echo "usage: $0 [-t SECONDS | -r RUNS] [TARGET...]" >&2; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  targets=(fuzz_scene fuzz_pack_spec fuzz_stl fuzz_mesh_vtu fuzz_mesh_msh fuzz_mesh_inp fuzz_mesh_medit
           fuzz_mesh_vtk fuzz_mesh_pvtu fuzz_mesh_tetgen)
fi

cxx=${CXX:-$(command -v clang++-14 || command -v clang++)}
build=${BUILD:-build-libfuzzer}
flags="-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
launcher=()
if command -v ccache > /dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi

cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER="$cxx" \
  -DCMAKE_CXX_FLAGS="$flags" -DCISAMR_LIBFUZZER=ON -DCISAMR_WITH_MPI=OFF "${launcher[@]}" > /dev/null
cmake --build "$build" -j"${JOBS:-2}" --target "${targets[@]}"

if [ -n "$runs" ]; then limit=(-runs="$runs"); else limit=(-max_total_time="$seconds"); fi
status=0
for target in "${targets[@]}"; do
  seeds=tests/fuzz/corpus/${target#fuzz_}
  mkdir -p "$build/fuzz-corpus/$target" "$build/fuzz-artifacts/$target"
  echo "== $target (${limit[*]})"
  # A reader must refuse, not grow: 512 MB for one allocation, 2 GB in all, 10 s per input.
  if ! "$build/tests/fuzz/$target" "${limit[@]}" -timeout=10 -malloc_limit_mb=512 -rss_limit_mb=2048 \
      -print_final_stats=1 -artifact_prefix="$build/fuzz-artifacts/$target/" \
      "$build/fuzz-corpus/$target" "$seeds"; then
    status=1
  fi
done
exit $status
