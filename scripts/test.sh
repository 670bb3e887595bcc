#!/usr/bin/env bash
# The whole test suite, as CI runs it:
#   1. gcc Release (-O3) build with -Werror, every cmocka suite and the CLI test under ctest
#   2. clang build with ASan + UBSan (-Werror), the same suites; any report fails
#   3. libFuzzer targets for every parser, FUZZ_SECONDS each (default 60) on a seed corpus
#   4. install, then build and run a consumer through find_package(xylem) and pkg-config
#   5. the smallest build: no OpenSubdiv, no GL, no Vulkan; the suites that do not subdivide
# Exits non-zero on the first failure.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh

jobs=$(nproc 2>/dev/null || echo 2)
fuzz_seconds=${FUZZ_SECONDS:-60}
passed=0
stage() { echo; echo "=== $* ==="; }

stage "1/5 gcc -O3 -Werror: ctest"
cmake -S . -B build-test -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_COMPILER=gcc \
  -DXYL_WERROR=ON >/dev/null
cmake --build build-test -j "$jobs"
ctest --test-dir build-test --output-on-failure -j "$jobs"
passed=$((passed + 1))

stage "2/5 clang ASan+UBSan: ctest"
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCMAKE_C_COMPILER=clang \
  -DXYL_WERROR=ON -DXYL_SANITIZE=ON >/dev/null
cmake --build build-asan -j "$jobs"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:strict_string_checks=1 \
UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build-asan --output-on-failure -j "$jobs"
passed=$((passed + 1))

stage "3/5 libFuzzer: ${fuzz_seconds}s per target"
cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
  -DXYL_BUILD_FUZZERS=ON -DXYL_BUILD_TESTS=ON >/dev/null
cmake --build build-fuzz -j "$jobs" --target fuzz_grammar fuzz_skel fuzz_leaf_obj fuzz_glb xylem_cli
corpus=$(mktemp -d)
trap 'rm -rf "$corpus"' EXIT
mkdir -p "$corpus/grammar" "$corpus/skel" "$corpus/leaf_obj" "$corpus/glb"
cp tests/data/grammars/*.lsys "$corpus/grammar/"
for p in $(./build-fuzz/samples/xylem presets | cut -d' ' -f1); do
  ./build-fuzz/samples/xylem preset "$p" > "$corpus/grammar/preset-$p.lsys"
done
cp tests/data/skel/*.skel "$corpus/skel/"
cp tests/data/leaves/*.obj "$corpus/leaf_obj/"
for k in 3 4; do  # xylem's own GLBs: quads to rejoin (k = 4), triangles too (k = 3)
  ./build-fuzz/samples/xylem mesh --preset abop-1.24a --sides "$k" --out "$corpus/glb/k$k.glb" >/dev/null
done
for target in grammar skel leaf_obj glb; do
  echo "fuzz_$target:"
  (cd "$corpus" && "$OLDPWD/build-fuzz/tests/fuzz_$target" -max_total_time="$fuzz_seconds" \
     -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 "$corpus/$target" 2>&1 |
     grep -E '^(stat::number_of_executed_units|stat::peak_rss_mb|==|SUMMARY|Done)' || true)
  # libFuzzer leaves crash-*/leak-*/timeout-* files in the working directory on failure
  if ls "$corpus"/crash-* "$corpus"/leak-* "$corpus"/timeout-* >/dev/null 2>&1; then
    echo "fuzz_$target found a failing input:"; ls "$corpus"/crash-* "$corpus"/leak-* "$corpus"/timeout-* 2>/dev/null
    exit 1
  fi
done
passed=$((passed + 1))

stage "4/5 install + consumer (find_package and pkg-config)"
prefix="$corpus/prefix"
cmake --install build-test --prefix "$prefix" >/dev/null
cmake -S tests/consumer -B "$corpus/consumer" -G Ninja -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build "$corpus/consumer"
"$corpus/consumer/consumer"
libdir=$(ls -d "$prefix"/lib*/pkgconfig | head -n 1)
PKG_CONFIG_PATH="$libdir" cc -std=c11 tests/consumer/main.c -o "$corpus/consumer_pc" \
  $(PKG_CONFIG_PATH="$libdir" pkg-config --cflags xylem) \
  $(PKG_CONFIG_PATH="$libdir" pkg-config --libs --static xylem)
LD_LIBRARY_PATH="$(dirname "$libdir")" "$corpus/consumer_pc"
passed=$((passed + 1))

stage "5/5 -DXYL_WITH_OPENSUBDIV=OFF -DXYL_WITH_GL=OFF -DXYL_WITH_VULKAN=OFF: ctest"
# Everything else builds; subdivision answers "not built" (test_mesh checks it). test_stems,
# the CLI tests and the glTF samples subdivide throughout, so they run in stages 1 and 2 only.
cmake -S . -B build-min -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_COMPILER=gcc \
  -DXYL_WERROR=ON -DXYL_WITH_OPENSUBDIV=OFF -DXYL_WITH_GL=OFF -DXYL_WITH_VULKAN=OFF >/dev/null
cmake --build build-min -j "$jobs"
ctest --test-dir build-min --output-on-failure -j "$jobs" \
  -E '^(test_stems|test_cli|stems_glb_samples|gltf_validator)$'
passed=$((passed + 1))

echo
echo "stages: $passed passed, 0 failed"
