#!/usr/bin/env bash
# A long libFuzzer run of one harness (see tests/fuzz/README.md):
#   tests/fuzz/run.sh BUILD_DIR READER SECONDS [libFuzzer flags...]
# BUILD_DIR was configured with CC=clang CXX=clang++ -DBS_FUZZ=ON. The corpus
# grows in BUILD_DIR/fuzz/corpus/READER (seeded from tests/data/fuzz/READER
# and the CMake seed list), crashes go to BUILD_DIR/fuzz/artifacts/READER/.
# Extra flags come last and win (e.g. -rss_limit_mb=4096 for long msh runs:
# Gmsh keeps ~27 KB per session, so the RSS grows by itself).
# One process on one core (no -jobs/-workers: with them libFuzzer forks a
# worker that logs to ./fuzz-0.log); run from the source tree, where the
# scene harness resolves data/ paths.
set -euo pipefail
build=$1 reader=$2 secs=$3
shift 3
exe=$build/tests/fuzz/fuzz_${reader}_libfuzzer
[ -x "$exe" ] || { echo "run.sh: no $exe (cmake --build $build --target fuzz_${reader}_libfuzzer)" >&2; exit 2; }
corpus=$build/fuzz/corpus/$reader artifacts=$build/fuzz/artifacts/$reader
mkdir -p "$corpus" "$artifacts"
cp -n tests/data/fuzz/"$reader"/* "$corpus"/ 2>/dev/null || true
case $reader in
  vtu) cp -n tests/data/vtu/*.vtu "$corpus"/ ;;
  scene) cp -n data/scenes/*.json "$corpus"/ ;;
esac
export ASAN_OPTIONS=${ASAN_OPTIONS:-allocator_may_return_null=1:detect_leaks=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tests/lsan.supp}
exec "$exe" "$corpus" -artifact_prefix="$artifacts/" -max_total_time="$secs" \
  -rss_limit_mb=2048 -malloc_limit_mb=1024 -timeout=20 -max_len=65536 -print_final_stats=1 "$@"
