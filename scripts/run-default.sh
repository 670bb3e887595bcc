#!/usr/bin/env bash
# The main job: builds xylem and grows the built-in default tree, writing out/tree.glb (glTF 2.0
# binary: its closed stem mesh and its leaves, textured, alpha-masked quads in leaf-collapse LOD
# order in 4 sectors, with the LOD tables in the leaves node's extras), out/foliage.csv (that LOD
# table: one row per LOD per sector), out/tree.png (the stem mesh refined by PN tessellation on
# the GPU and its leaves at the LOD the pixel budget allows, headless: EGL, llvmpipe where there
# is no GPU), out/tree.skel (the skeleton text
# format) and out/tree.obj (skeleton polylines for any viewer).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cmake -S . -B build-release -G Ninja -DCMAKE_BUILD_TYPE=Release -DXYL_BUILD_TESTS=OFF >/dev/null
cmake --build build-release --target xylem_cli >/dev/null
mkdir -p out
./build-release/samples/xylem mesh --foliage --sectors 4 --out out/tree.glb --table out/foliage.csv
./build-release/samples/xylem render --out out/tree.png
./build-release/samples/xylem skeleton --out out/tree.skel >/dev/null
./build-release/samples/xylem skeleton --out out/tree.obj >/dev/null
echo "wrote out/tree.skel and out/tree.obj"
