#!/usr/bin/env bash
# Writes every preset's stem mesh as .glb into $1 (plain, and with one Catmull-Clark and one Loop
# level), and its leaves alone and with the stems (with the CLI's leaf texture), for the
# gltf_validator test, and its chain of stem LODs (one file, MSFT_lod). $XYLEM is the CLI.
set -euo pipefail
: "${XYLEM:?set XYLEM to the xylem binary}"
out=$1
mkdir -p "$out"
for p in $("$XYLEM" presets | cut -d' ' -f1); do
  "$XYLEM" mesh --preset "$p" --out "$out/stems-$p.glb" >/dev/null
  "$XYLEM" mesh --preset "$p" --subdivide catmark --out "$out/stems-$p-catmark.glb" >/dev/null
  "$XYLEM" mesh --preset "$p" --subdivide loop --sides 6 --out "$out/stems-$p-loop.glb" >/dev/null
  "$XYLEM" foliage --preset "$p" --sectors 4 --out "$out/leaves-$p.glb" >/dev/null
  "$XYLEM" mesh --preset "$p" --foliage --out "$out/tree-$p.glb" >/dev/null
  "$XYLEM" mesh --preset "$p" --lods 8 --out "$out/lods-$p.glb" >/dev/null
done
echo "wrote $(ls "$out"/stems-*.glb | wc -l) preset meshes, $(ls "$out"/lods-*.glb | wc -l) LOD chains and $(ls "$out"/leaves-*.glb "$out"/tree-*.glb | wc -l) leafy files to $out"
