#!/usr/bin/env bash
# The CLI's interface: commands, outputs, exit codes and error messages. $XYLEM is the binary.
set -uo pipefail
: "${XYLEM:?set XYLEM to the xylem binary}"
data="$(cd "$(dirname "$0")" && pwd)/data"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
passed=0
failed=0

# expect CODE DESCRIPTION -- command...   (stdout+stderr saved in $tmp/out)
expect() {
  local want=$1 what=$2
  shift 3
  "$@" >"$tmp/out" 2>&1
  local got=$?
  if [ "$got" -eq "$want" ]; then
    passed=$((passed + 1))
  else
    failed=$((failed + 1))
    echo "FAIL: $what: exit $got, expected $want"
    sed 's/^/    /' "$tmp/out" | head -20
  fi
}
# xview ARGS...: the command under a private X server, with the command's own exit status
# (xvfb-run exits 5 instead when it fails to remove its temporary directory, which happens
# under load when the command exits while the server is still starting)
xview() {
  rm -f "$tmp/xview_rc"
  xvfb-run -a bash -c '"$@"; echo $? >"$XVIEW_RC"' xview "$@"
  local x=$?
  if [ -s "$tmp/xview_rc" ]; then
    x=$(cat "$tmp/xview_rc")
    rm -f "$tmp/xview_rc"
  fi
  return "$x"
}
export XVIEW_RC="$tmp/xview_rc"
# ok / bad DESCRIPTION: count a check made by hand
ok() { passed=$((passed + 1)); }
bad() { failed=$((failed + 1)); echo "FAIL: $1"; }
# contains TEXT DESCRIPTION: the last command's output holds TEXT
contains() {
  if grep -qF -- "$1" "$tmp/out"; then passed=$((passed + 1)); else
    failed=$((failed + 1)); echo "FAIL: $2: output lacks '$1'"; sed 's/^/    /' "$tmp/out" | head -20; fi
}

expect 0 "help" -- "$XYLEM" --help
contains "usage: xylem" "help text"
expect 64 "no command" -- "$XYLEM"
expect 64 "unknown command" -- "$XYLEM" frobnicate
expect 0 "presets" -- "$XYLEM" presets
contains "(default)" "presets mark the default"
contains "abop-1.24a" "presets list ABOP 1.24a"
grep -Eq '^abop-2\.8-ternary +[1-9][0-9]* leaves ' "$tmp/out" && grep -Eq '^abop-1\.24a +0 leaves ' "$tmp/out" &&
  passed=$((passed + 1)) || { failed=$((failed + 1)); echo "FAIL: presets show their leaf counts"; }
expect 0 "preset text" -- "$XYLEM" preset abop-1.24a
contains "F -> F[+F]F[-F]F" "preset text is the grammar"
expect 64 "unknown preset" -- "$XYLEM" preset nope

expect 0 "derive depth 1" -- "$XYLEM" derive --preset abop-1.24a --depth 1
[ "$(cat "$tmp/out")" = "F[+F]F[-F]F" ] && passed=$((passed + 1)) || { failed=$((failed + 1)); echo "FAIL: derive output: $(cat "$tmp/out")"; }
expect 0 "derive parametric" -- "$XYLEM" derive --preset abop-2.6-monopodial --depth 1
contains '!(0.6)F(1)[&(45)B(0.6,0.4242)L(0.25)[&(50)$L(0.25)]/(90)' "parametric output with parameters"
contains ']/(137.5)A(0.9,0.4242)L(0.25)[' "parametric output: the trunk apex and its leaves"
expect 0 "derive a file" -- "$XYLEM" derive --grammar "$data/grammars/parametric.lsys" --depth 2
expect 0 "seeded derive" -- "$XYLEM" derive --preset abop-1.28-stochastic --seed 3
cp "$tmp/out" "$tmp/seed3"
"$XYLEM" derive --preset abop-1.28-stochastic --seed 3 >"$tmp/seed3b"
"$XYLEM" derive --preset abop-1.28-stochastic --seed 4 >"$tmp/seed4"
cmp -s "$tmp/seed3" "$tmp/seed3b" && passed=$((passed + 1)) || { failed=$((failed + 1)); echo "FAIL: equal seeds differ"; }
cmp -s "$tmp/seed3" "$tmp/seed4" && { failed=$((failed + 1)); echo "FAIL: different seeds agree"; } || passed=$((passed + 1))

printf 'axiom: F\nF -> F[+F\n' >"$tmp/bad.lsys"
expect 65 "broken grammar" -- "$XYLEM" derive --grammar "$tmp/bad.lsys"
contains "bad.lsys:2:7: invalid grammar: '[' is never closed" "error names file, line, column"
expect 66 "missing grammar file" -- "$XYLEM" derive --grammar "$tmp/none.lsys"
: >"$tmp/empty.lsys"
expect 65 "empty grammar file" -- "$XYLEM" derive --grammar "$tmp/empty.lsys"
expect 64 "bad depth" -- "$XYLEM" derive --depth -1
expect 64 "preset and grammar" -- "$XYLEM" derive --preset abop-1.24a --grammar x
expect 65 "depth over the limit" -- "$XYLEM" derive --preset abop-1.24a --depth 1000
contains "limit" "limit message"
printf 'axiom: A(1)\nA(x) -> A(x-1)B(1/(x-1))\n' >"$tmp/nan.lsys"
expect 65 "division by zero" -- "$XYLEM" derive --grammar "$tmp/nan.lsys" --depth 3
contains "non-finite" "non-finite message"
# 71: the allocator runs dry. Depth 11 of abop-1.24a needs about 280 MB; the address space is
# capped below that. Not under AddressSanitizer, which reserves terabytes of address space.
# (grep -c reads all of nm's output: with -q, nm would die of SIGPIPE and pipefail fail the test)
if ldd "$XYLEM" 2>/dev/null | grep -c libasan >/dev/null ||
   nm "$XYLEM" 2>/dev/null | grep -c __asan_init >/dev/null; then
  echo "test_cli: out of memory (71) not checked under AddressSanitizer"
else
  expect 71 "out of memory" -- bash -c 'ulimit -v 120000 && exec "$0" derive --preset abop-1.24a --depth 11' "$XYLEM"
  contains "abop-1.24a: out of memory" "out of memory names the source"
fi

expect 0 "skeleton .skel" -- "$XYLEM" skeleton --out "$tmp/tree.skel"
contains "nodes" "summary counts nodes"
contains "time:" "summary shows time"
head -n 1 "$tmp/tree.skel" | grep -q "xylem-skeleton 1" && passed=$((passed + 1)) || { failed=$((failed + 1)); echo "FAIL: .skel header"; }
expect 0 "skeleton .obj" -- "$XYLEM" skeleton --preset faycal-leaves --out "$tmp/tree.obj"
grep -q '^l ' "$tmp/tree.obj" && passed=$((passed + 1)) || { failed=$((failed + 1)); echo "FAIL: obj has no polylines"; }
expect 0 "murray angles" -- "$XYLEM" skeleton --preset abop-2.7-sympodial --angles murray --radius-exponent 3 --out "$tmp/m.skel"
expect 0 "murray clamps at n = 2" -- "$XYLEM" skeleton --preset abop-2.7-sympodial --angles murray --radius-exponent 2 --out "$tmp/m2.skel"
contains "warning: " "clamping is reported"
expect 0 "grammar radii" -- "$XYLEM" skeleton --preset abop-2.6-monopodial --radius grammar --merge-collinear --out "$tmp/g.skel"
expect 64 "bad exponent" -- "$XYLEM" skeleton --radius-exponent 0 --out "$tmp/x.skel"
expect 64 "bad angles" -- "$XYLEM" skeleton --angles sideways --out "$tmp/x.skel"
expect 64 "missing --out" -- "$XYLEM" skeleton
expect 64 "bad extension" -- "$XYLEM" skeleton --out "$tmp/tree.png"
expect 73 "unwritable output" -- "$XYLEM" skeleton --out "$tmp/no/such/dir/tree.skel"
[ -z "$(ls "$tmp" | grep tmp-)" ] && passed=$((passed + 1)) || { failed=$((failed + 1)); echo "FAIL: temporary files left behind"; }

expect 0 "mesh .glb" -- "$XYLEM" mesh --out "$tmp/tree.glb"
contains "vertices" "mesh summary"
head -c 4 "$tmp/tree.glb" | grep -q "glTF" && passed=$((passed + 1)) || { failed=$((failed + 1)); echo "FAIL: .glb magic"; }
expect 0 "mesh .obj from a .skel" -- "$XYLEM" mesh --skeleton "$data/stems/spokes_8.skel" --sides 6 --out "$tmp/s.obj"
grep -q '^f ' "$tmp/s.obj" && passed=$((passed + 1)) || { failed=$((failed + 1)); echo "FAIL: obj has no faces"; }
expect 0 "mesh subdivided" -- "$XYLEM" mesh --preset faycal-leaves --subdivide catmark --normals smooth --out "$tmp/f.glb"
expect 64 "sides above 32" -- "$XYLEM" mesh --sides 40 --out "$tmp/x.glb"
expect 0 "odd sides" -- "$XYLEM" mesh --sides 5 --out "$tmp/odd.glb"
contains "triangles" "odd sides summary"
expect 64 "sides below 3" -- "$XYLEM" mesh --sides 2 --out "$tmp/x.glb"
expect 64 "bad subdivision" -- "$XYLEM" mesh --subdivide cubic --out "$tmp/x.glb"
expect 0 "checked joints" -- "$XYLEM" mesh --preset faycal-leaves --out "$tmp/f.glb"
contains "intersecting pairs at joints in the construction; repaired in" "joint summary says what it found and repaired"
contains "laterals start later" "joint summary"
contains "faces kept" "joint summary counts the faces kept"
contains "the written mesh has 0 intersecting pairs at joints" "joint summary says what the written mesh holds"
expect 0 "clean joints" -- "$XYLEM" mesh --out "$tmp/t.glb"
contains "found no intersecting pair at a joint (1 build)" "joint summary of a clean construction"
expect 0 "unchecked joints" -- "$XYLEM" mesh --preset faycal-leaves --joints unchecked --out "$tmp/f.glb"
grep -qF "laterals start later" "$tmp/out" && { failed=$((failed + 1)); echo "FAIL: unchecked build reports joints"; } || passed=$((passed + 1))
expect 64 "bad joint check" -- "$XYLEM" mesh --joints some --out "$tmp/x.glb"
# --base: the default tree stands on y = 0 (its root) with a closed or an open base; the open
# .obj has one face fewer (the root's cap, one quad at k = 4).
expect 0 "closed base" -- "$XYLEM" mesh --base closed --out "$tmp/closed.obj"
expect 0 "open base" -- "$XYLEM" mesh --base open --out "$tmp/open.obj"
for f in closed open; do
    low=$(awk '/^v /{if (m == "" || $3 < m) m = $3} END {print m}' "$tmp/$f.obj")
    [ "$low" = "0" ] && passed=$((passed + 1)) || { failed=$((failed + 1)); echo "FAIL: $f base: lowest y $low, not 0"; }
done
fc=$(grep -c '^f ' "$tmp/closed.obj"); fo=$(grep -c '^f ' "$tmp/open.obj")
[ "$fo" -eq $((fc - 1)) ] && passed=$((passed + 1)) || { failed=$((failed + 1)); echo "FAIL: open base has $fo faces, closed $fc"; }
expect 64 "bad base" -- "$XYLEM" mesh --base flat --out "$tmp/x.glb"
# Stem LODs: one .glb, or one .obj per LOD, each LOD's budget, error, nodes and faces printed.
expect 0 "stem LODs .glb" -- "$XYLEM" mesh --preset abop-2.8-ternary --lods 4 --out "$tmp/lods.glb"
contains "4 stem LODs" "the LOD count"
contains "lod  budget        error         pruned        rings         nodes    faces" "the LOD table"
contains "wrote $tmp/lods.glb (4 LODs, MSFT_lod)" "one file for the chain"
expect 0 "stem LODs .obj" -- "$XYLEM" mesh --preset abop-1.24a --lods 3 --lod-error 0.05 --out "$tmp/lods.obj"
for i in 0 1 2; do
    [ -s "$tmp/lods-lod$i.obj" ] && ok || bad "no lods-lod$i.obj"
done
f0=$(grep -c '^f ' "$tmp/lods-lod0.obj"); f2=$(grep -c '^f ' "$tmp/lods-lod2.obj")
[ "$f2" -lt "$f0" ] && ok || bad "LOD 2 has $f2 faces, LOD 0 $f0"
expect 64 "no LODs" -- "$XYLEM" mesh --lods 0 --out "$tmp/x.glb"
expect 64 "too many LODs" -- "$XYLEM" mesh --lods 13 --out "$tmp/x.glb"
expect 64 "negative LOD error" -- "$XYLEM" mesh --lods 2 --lod-error -1 --out "$tmp/x.glb"
expect 64 "LOD error without LODs" -- "$XYLEM" mesh --lod-error 1 --out "$tmp/x.glb"
expect 64 "LODs with foliage" -- "$XYLEM" mesh --lods 2 --foliage --out "$tmp/x.glb"
expect 64 "mesh needs --out" -- "$XYLEM" mesh
expect 64 "skeleton and preset" -- "$XYLEM" mesh --skeleton "$data/stems/spokes_8.skel" --preset abop-1.24a --out "$tmp/x.glb"
expect 66 "missing skeleton" -- "$XYLEM" mesh --skeleton "$tmp/none.skel" --out "$tmp/x.glb"
expect 65 "broken skeleton" -- "$XYLEM" mesh --skeleton "$data/skel/bad_parent.skel" --out "$tmp/x.glb"
# A format version the reader does not know is bad input (65), not a missing backend (69).
expect 65 "unknown .skel version" -- "$XYLEM" mesh --skeleton "$data/skel/bad_version.skel" --out "$tmp/x.glb"
contains "version" "unknown .skel version names the version"
[ ! -e "$tmp/x.glb" ] && passed=$((passed + 1)) || { failed=$((failed + 1)); echo "FAIL: unknown .skel version wrote output"; }
expect 65 "unknown .skel version (foliage)" -- "$XYLEM" foliage --skeleton "$data/skel/bad_version.skel" --out "$tmp/x.glb"
expect 73 "unwritable mesh" -- "$XYLEM" mesh --out "$tmp/no/dir/x.glb"
# Exit codes per error kind of a skeleton file: 66 unreadable (a directory), 65 a number no float
# holds, and a mesh that leaves the float range fails in the stage that makes it, naming the
# input, not the output.
expect 66 "skeleton that is a directory" -- "$XYLEM" mesh --skeleton "$tmp" --out "$tmp/x.glb"
printf 'xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 1e39 0 1\nend\n' >"$tmp/huge_number.skel"
expect 65 "skeleton with a number too large for a float" -- "$XYLEM" mesh --skeleton "$tmp/huge_number.skel" --out "$tmp/x.glb"
contains "huge_number.skel:4:" "a non-finite number names the line"
printf 'xylem-skeleton 1\nnodes 2\nleaves 0\nn 0 -1 0 0 0 3e38\nn 1 0 0 3e38 0 3e38\nend\n' >"$tmp/overflow.skel"
rm -f "$tmp/x.obj"
expect 65 "rings beyond the float range" -- "$XYLEM" mesh --skeleton "$tmp/overflow.skel" --subdivide catmark --out "$tmp/x.obj"
contains "overflow.skel: non-finite number: the stem mesher: vertex" "the failing stage and the input are named"
grep -q "x.obj" "$tmp/out" && bad "the error names the output" || ok
[ ! -e "$tmp/x.obj" ] && ok || bad "a failed mesh wrote x.obj"
# Length / radius of 1e40: texture coordinates stay finite and the OBJ is written.
printf 'xylem-skeleton 1\nnodes 2\nleaves 0\nn 0 -1 0 0 0 1e-40\nn 1 0 0 1 0 1e-40\nend\n' >"$tmp/needle.skel"
expect 0 "a needle of radius 1e-40" -- "$XYLEM" mesh --skeleton "$tmp/needle.skel" --out "$tmp/needle.obj"
grep -Eiq '^vt .*(inf|nan)' "$tmp/needle.obj" && bad "needle UVs not finite" || ok
# World coordinates: a tree 1e5 units away keeps its 1e-3 twig; OBJ and .skel print world
# positions, the GLB node carries the origin.
printf 'xylem-skeleton 1\nnodes 3\nleaves 0\nn 0 -1 100000.0123 5 -7 0.01\nn 1 0 100000.0123 6 -7 0.002\nn 2 1 100000.0133 6.001 -7 0.001\nend\n' >"$tmp/far.skel"
expect 0 "a far skeleton meshes" -- "$XYLEM" mesh --skeleton "$tmp/far.skel" --out "$tmp/far.obj"
grep -q "warning" "$tmp/out" && bad "a far skeleton with an origin warns" || ok
grep -Eq '^v 100000\.0[0-9]* ' "$tmp/far.obj" && ok || bad "far OBJ has world positions"
expect 0 "a far skeleton as .glb" -- "$XYLEM" mesh --skeleton "$tmp/far.skel" --out "$tmp/far.glb"
grep -aq '"translation":\[100000.0123,5,-7\]' "$tmp/far.glb" && ok || bad "far GLB node translation"
# --origin plants a grown tree: world positions in .skel, the origin in the GLB, the same mesh.
expect 0 "a tree planted far away" -- "$XYLEM" skeleton --preset abop-1.24a --origin 100000.0123,0,-2e7 --out "$tmp/planted.skel"
grep -q '^n 0 -1 100000.0123 0 -20000000 ' "$tmp/planted.skel" && ok || bad "planted .skel starts at the origin"
expect 0 "the planted tree meshes" -- "$XYLEM" mesh --skeleton "$tmp/planted.skel" --out "$tmp/planted.glb"
"$XYLEM" mesh --preset abop-1.24a --out "$tmp/at0.glb" >/dev/null 2>&1
grep -aq '"translation":\[100000.0123,0,-20000000\]' "$tmp/planted.glb" && ok || bad "planted GLB translation"
# the binary chunks match: the files differ only by the translation in the JSON
cmp -s <(tail -c 65536 "$tmp/planted.glb") <(tail -c 65536 "$tmp/at0.glb") && ok || bad "planted mesh differs from the mesh at the origin"
expect 64 "bad --origin" -- "$XYLEM" skeleton --origin 1,2 --out "$tmp/x.skel"
expect 64 "--origin with --skeleton" -- "$XYLEM" mesh --skeleton "$tmp/far.skel" --origin 1,2,3 --out "$tmp/x.glb"
# A forest around the world's origin keeps origin 0; its far twig is reported with the figures.
printf 'xylem-skeleton 1\nnodes 4\nleaves 0\nn 0 -1 0 0 0 0.5\nn 1 0 0 1 0 0.4\nn 2 -1 100000 0 0 0.01\nn 3 2 100000 1 0 0.01\nend\n' >"$tmp/forest.skel"
expect 0 "a forest with a far twig" -- "$XYLEM" mesh --skeleton "$tmp/forest.skel" --out "$tmp/forest.obj"
contains "warning: $tmp/forest.skel: the skeleton loses detail to float precision: node 2" "the reader warns with the node"
contains "floats are spaced 0.0078125, 78.1 % of its radius 0.01" "the warning gives the figures"

# foliage: leaves, their LODs, a .glb and the LOD table
expect 0 "foliage with sectors and a table" -- "$XYLEM" foliage --sectors 4 --out "$tmp/leaves.glb" --table "$tmp/lods.csv"
contains "5103 leaves -> " "foliage summary counts leaves"
contains "4 sectors" "foliage summary names the sectors"
contains "time: skeleton" "foliage summary shows time"
head -c 4 "$tmp/leaves.glb" | grep -q "glTF" && ok || bad "foliage .glb magic"
grep -qa '"mimeType":"image/png"' "$tmp/leaves.glb" && ok || bad "the leaf texture is embedded by default"
grep -qa '"name":"stems"' "$tmp/leaves.glb" && bad "'foliage' wrote stems" || ok
[ "$(head -n 1 "$tmp/lods.csv")" = "sector,lod,leaves,a,b,c,error" ] && ok || bad "table header"
# one row per LOD per sector: n - S merges + S = n rows; leaves = a + c; LOD 0 of each sector
# has no error, and the errors never decrease within a sector
awk -F, 'NR > 1 { rows++; if ($3 != $4 + $6) bad = 1; if ($2 == 0 && $7 != 0) bad = 1;
         if ($2 > 0 && $7 + 0 < last) bad = 1; last = $7 + 0; s[$1] = 1 }
         END { exit (bad || rows != 5103 || length(s) != 4) }' "$tmp/lods.csv" && ok || bad "table rows"
"$XYLEM" skeleton --preset faycal-leaves --out "$tmp/fl.skel" >/dev/null
expect 0 "foliage from a .skel" -- "$XYLEM" foliage --skeleton "$tmp/fl.skel" --aspect 0.3 --out "$tmp/fl.glb"
contains "255 leaves -> 509 in the LOD array, 1 sector" "leaves of the skeleton's attachments"
expect 0 "foliage with a given texture" -- "$XYLEM" foliage --preset faycal-leaves --leaf-texture "$data/../../docs/img/bench_tess.png" --out "$tmp/tex.glb"
size=$(stat -c %s "$data/../../docs/img/bench_tess.png")
grep -qa "\"byteLength\":$size}" "$tmp/tex.glb" && ok || bad "the given texture is embedded whole"
expect 0 "foliage of a source without leaves" -- "$XYLEM" foliage --preset abop-1.24a --sectors 2 --out "$tmp/noleaf.glb" --table "$tmp/noleaf.csv"
contains "no leaf attachments" "no-leaf message"
[ "$(tail -n +2 "$tmp/noleaf.csv")" = "$(printf '0,0,0,0,0,0,0\n1,0,0,0,0,0,0')" ] && ok || bad "no-leaf table: one empty LOD a sector"
grep -qa '"meshes"' "$tmp/noleaf.glb" && bad "a file without leaves has a mesh" || ok
expect 64 "foliage needs --out" -- "$XYLEM" foliage
expect 64 "foliage writes .glb" -- "$XYLEM" foliage --out "$tmp/x.obj"
expect 64 "foliage sectors 0" -- "$XYLEM" foliage --sectors 0 --out "$tmp/x.glb"
expect 64 "foliage sectors above 256" -- "$XYLEM" foliage --sectors 257 --out "$tmp/x.glb"
expect 64 "foliage bad aspect" -- "$XYLEM" foliage --aspect 0 --out "$tmp/x.glb"
expect 64 "foliage aspect not a number" -- "$XYLEM" foliage --aspect wide --out "$tmp/x.glb"
expect 64 "foliage table not .csv" -- "$XYLEM" foliage --table "$tmp/t.txt" --out "$tmp/x.glb"
expect 64 "foliage texture not .png" -- "$XYLEM" foliage --leaf-texture "$tmp/t.jpg" --out "$tmp/x.glb"
expect 64 "foliage skeleton and preset" -- "$XYLEM" foliage --skeleton "$tmp/fl.skel" --preset abop-1.24a --out "$tmp/x.glb"
expect 64 "foliage options need foliage" -- "$XYLEM" mesh --sectors 4 --out "$tmp/x.glb"
expect 64 "--foliage is mesh's" -- "$XYLEM" skeleton --foliage --out "$tmp/x.skel"
expect 64 "mesh --foliage writes .glb" -- "$XYLEM" mesh --foliage --out "$tmp/x.obj"
expect 66 "foliage missing texture" -- "$XYLEM" foliage --leaf-texture "$tmp/none.png" --out "$tmp/x.glb"
printf 'not a png' >"$tmp/fake.png"
expect 65 "foliage texture that is no PNG" -- "$XYLEM" foliage --leaf-texture "$tmp/fake.png" --out "$tmp/x.glb"
contains "not a PNG file" "fake texture message"
[ ! -e "$tmp/x.glb" ] && ok || bad "a refused foliage wrote x.glb"
expect 73 "foliage unwritable output" -- "$XYLEM" foliage --out "$tmp/no/dir/x.glb"
expect 73 "foliage unwritable table" -- "$XYLEM" foliage --preset faycal-leaves --out "$tmp/t.glb" --table "$tmp/no/dir/t.csv"
[ -z "$(ls "$tmp" | grep tmp-)" ] && ok || bad "temporary files left behind"
expect 0 "mesh with foliage" -- "$XYLEM" mesh --foliage --sectors 2 --out "$tmp/leafy.glb" --table "$tmp/leafy.csv"
contains "vertices" "mesh summary with foliage"
contains "5103 leaves -> " "foliage summary with the mesh"
grep -qa '"nodes":\[{"name":"stems","mesh":0},{"name":"leaves","mesh":1,' "$tmp/leafy.glb" && ok || bad "stems and leaves nodes"
[ "$(wc -l <"$tmp/leafy.csv")" -eq 5104 ] && ok || bad "mesh --foliage table rows"
# leaves from an OBJ leaf mesh, a template leaf, the viewpoint-driven cost
leaves="$data/leaves"
expect 0 "foliage from a leaf mesh" -- "$XYLEM" foliage --leaf-mesh "$leaves/broadleaf.obj" --out "$tmp/lm.glb" --table "$tmp/lm.csv"
contains "broadleaf.obj: 6 leaves -> 11 in the LOD array" "leaf mesh summary"
[ "$(wc -l <"$tmp/lm.csv")" -eq 7 ] && ok || bad "leaf mesh table rows"
expect 0 "mesh with a leaf mesh" -- "$XYLEM" mesh --foliage --leaf-mesh "$leaves/broadleaf.obj" --out "$tmp/lm2.glb"
contains "6 leaves -> " "mesh --foliage --leaf-mesh summary"
expect 0 "foliage with a template leaf and the viewpoint cost" -- "$XYLEM" foliage --preset faycal-leaves --leaf-template "$leaves/template_leaf.obj" --cost viewpoint --out "$tmp/tv.glb" --table "$tmp/tv.csv"
contains "leaves -> " "template summary"
expect 0 "the same with the hidalgo cost" -- "$XYLEM" foliage --preset faycal-leaves --leaf-template "$leaves/template_leaf.obj" --cost hidalgo --out "$tmp/th.glb" --table "$tmp/th.csv"
cmp -s "$tmp/tv.csv" "$tmp/th.csv" && bad "the two costs gave the same LOD table" || ok
expect 65 "a template of several leaves" -- "$XYLEM" foliage --leaf-template "$leaves/broadleaf.obj" --out "$tmp/x.glb"
contains "one leaf" "template message"
expect 64 "leaf mesh and a source" -- "$XYLEM" foliage --leaf-mesh "$leaves/broadleaf.obj" --preset abop-1.24a --out "$tmp/x.glb"
expect 64 "leaf mesh and template" -- "$XYLEM" foliage --leaf-mesh "$leaves/broadleaf.obj" --leaf-template "$leaves/template_leaf.obj" --out "$tmp/x.glb"
expect 64 "template and aspect" -- "$XYLEM" foliage --leaf-template "$leaves/template_leaf.obj" --aspect 0.3 --out "$tmp/x.glb"
expect 64 "leaf mesh not .obj" -- "$XYLEM" foliage --leaf-mesh "$leaves/broadleaf.txt" --out "$tmp/x.glb"
expect 64 "bad cost" -- "$XYLEM" foliage --cost fast --out "$tmp/x.glb"
expect 64 "cost needs foliage" -- "$XYLEM" mesh --cost viewpoint --out "$tmp/x.glb"
expect 66 "missing leaf mesh" -- "$XYLEM" foliage --leaf-mesh "$tmp/none.obj" --out "$tmp/x.glb"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n' >"$tmp/broken.obj"
expect 65 "leaf mesh with a bad face" -- "$XYLEM" foliage --leaf-mesh "$tmp/broken.obj" --out "$tmp/x.glb"
contains "broken.obj" "bad leaf mesh names the file"
[ ! -e "$tmp/x.glb" ] && ok || bad "a refused leaf mesh wrote x.glb"

if [ "${XYL_CLI_GPU:-0}" != 1 ]; then  # a build without the GL and Vulkan backends
  expect 69 "render without backends" -- "$XYLEM" render --size 16x16 --out "$tmp/x.png"
  contains "built without" "render says why"
  echo "test_cli: $passed passed, $failed failed (render and view: not built)"
  [ "$failed" -eq 0 ]
  exit
fi

# render: headless GPU (llvmpipe / lavapipe without one); small images keep it quick
png_magic() { head -c 8 "$1" | od -An -tx1 | tr -d ' \n' | grep -q '^89504e470d0a1a0a$'; }
expect 0 "render default (GL, instanced)" -- "$XYLEM" render --size 64x48 --out "$tmp/t.png"
contains "triangles drawn" "render summary"
png_magic "$tmp/t.png" && passed=$((passed + 1)) || { failed=$((failed + 1)); echo "FAIL: render wrote no PNG"; }
expect 0 "render hardware path, wireframe" -- "$XYLEM" render --tess hardware --wireframe --level 2 --size 64x64 --out "$tmp/h.png"
expect 0 "render Vulkan from a .glb" -- "$XYLEM" render --mesh "$tmp/tree.glb" --backend vulkan --variant circle --size 64x64 --out "$tmp/v.png"
contains "(Vulkan)" "Vulkan device named"
expect 0 "render stems of a leafy .glb" -- "$XYLEM" render --mesh "$tmp/leafy.glb" --size 32x32 --out "$tmp/l.png"
contains "patches: 11646 (11646 quads)" "the leaves are not refined as stems"
expect 0 "render CPU reference" -- "$XYLEM" render --tess cpu --error-px 2 --camera 90,20 --size 64x64 --out "$tmp/c.png"
# --error-px given: one budget prunes, picks ring sides and tessellation levels; a far camera
# (16 times the framing distance) draws far fewer triangles than the framed one
expect 0 "render --error-px near" -- "$XYLEM" render --tess cpu --error-px 1 --foliage none --size 128x128 --out "$tmp/bn.png"
contains "budget: 1 px = " "render --error-px prints its world budget"
contains "sides: error " "render --error-px prints its ring sides"
near=$(sed -n 's/.* \([0-9]*\) triangles drawn$/\1/p' "$tmp/out")
expect 0 "render --error-px far" -- "$XYLEM" render --tess cpu --error-px 1 --foliage none --camera 30,10,16 --size 128x128 --out "$tmp/bf.png"
contains "nodes (" "render --error-px prints what it pruned"
far=$(sed -n 's/.* \([0-9]*\) triangles drawn$/\1/p' "$tmp/out")
[ -n "$near" ] && [ -n "$far" ] && [ $((far * 10)) -lt "$near" ] && ok || bad "--error-px far drew $far triangles, near $near"
grep -q "pruned twigs under .*: 0 of" "$tmp/out" && bad "--error-px far pruned nothing" || ok
for px in nan 0 -1 inf; do
  expect 64 "render --error-px $px" -- "$XYLEM" render --error-px "$px" --out "$tmp/x.png"
  contains "--error-px takes a positive number of pixels" "--error-px $px says why"
done
expect 65 "render an unknown .skel version" -- "$XYLEM" render --skeleton "$data/skel/bad_version.skel" --size 16x16 --out "$tmp/x.png"
[ ! -e "$tmp/x.png" ] && ok || bad "a refused skeleton wrote x.png"
expect 64 "render needs a .png" -- "$XYLEM" render --out "$tmp/x.jpg"
expect 64 "render level out of range" -- "$XYLEM" render --level 65 --out "$tmp/x.png"
expect 64 "render bad backend" -- "$XYLEM" render --backend metal --out "$tmp/x.png"
expect 64 "render bad size" -- "$XYLEM" render --size 0x10 --out "$tmp/x.png"
expect 64 "render bad camera" -- "$XYLEM" render --camera 0,95 --out "$tmp/x.png"
expect 64 "render hardware on Vulkan" -- "$XYLEM" render --backend vulkan --tess hardware --out "$tmp/x.png"
expect 66 "render missing mesh" -- "$XYLEM" render --mesh "$tmp/none.glb" --out "$tmp/x.png"
head -c 200 "$tmp/tree.glb" >"$tmp/trunc.glb"
expect 65 "render truncated mesh" -- "$XYLEM" render --mesh "$tmp/trunc.glb" --out "$tmp/x.png"
[ ! -e "$tmp/x.png" ] && passed=$((passed + 1)) || { failed=$((failed + 1)); echo "FAIL: a failed render left x.png"; }
expect 73 "render unwritable output" -- "$XYLEM" render --size 16x16 --out "$tmp/no/dir/x.png"

# render with leaves: the default tree's leaves are drawn unless --foliage none; the picture
# then has leaf-green pixels (tests/png_pixels.mjs counts them) where the bare tree has none
pixels="$(cd "$(dirname "$0")" && pwd)/png_pixels.mjs"
expect 0 "render leaves (default: lod)" -- "$XYLEM" render --size 96x96 --out "$tmp/leafy.png"
contains "leaves: --foliage lod: LOD " "render names the leaf LOD"
contains "leaves drawn" "render counts the leaves drawn"
expect 0 "render all leaves" -- "$XYLEM" render --foliage full --size 96x96 --out "$tmp/full.png"
contains "LOD 0 of 0..5102, 5103 of 5103 leaves drawn" "--foliage full draws every leaf"
expect 0 "render bare stems" -- "$XYLEM" render --foliage none --size 96x96 --out "$tmp/bare.png"
grep -q "^leaves:" "$tmp/out" && bad "--foliage none still drew leaves" || ok
if command -v node >/dev/null; then
  read -r n_leafy g_leafy < <(node "$pixels" "$tmp/leafy.png")
  read -r n_bare g_bare < <(node "$pixels" "$tmp/bare.png")
  [ "$n_leafy" -eq 9216 ] && [ "$g_leafy" -gt 500 ] && [ "$g_bare" -eq 0 ] && ok ||
    bad "leaf-green pixels: $g_leafy of $n_leafy with leaves, $g_bare of $n_bare without"
else
  bad "node (scripts/setup.sh installs it) is needed to read the rendered leaves back"
fi
cmp -s "$tmp/leafy.png" "$tmp/bare.png" && bad "leaves changed nothing" || ok
# from ten times the framing distance the tree is small but drawn (the far plane once stayed
# where it was and the picture came out empty)
expect 0 "render from far away" -- "$XYLEM" render --camera 30,10,10 --size 256x256 --out "$tmp/far.png"
if command -v node >/dev/null; then
  read -r n_far g_far < <(node "$pixels" "$tmp/far.png")
  [ "$g_far" -gt 20 ] && ok || bad "from far away: $g_far leaf-green pixels of $n_far"
fi
expect 0 "render leaves, hardware path, wireframe" -- "$XYLEM" render --tess hardware --wireframe --camera 40,20,0.5 --size 64x64 --out "$tmp/hl.png"
# per-leaf LOD: the GPU's cut draws fewer leaves than there are from a distance, and leaves
expect 0 "render per-leaf LOD" -- "$XYLEM" render --foliage adaptive --camera 30,20,1.5 --size 96x96 --out "$tmp/adaptive.png"
contains "leaves: --foliage adaptive: " "render names the per-leaf mode"
drawn="$(sed -n 's/.* \([0-9]*\) of 5103 leaves drawn.*/\1/p' "$tmp/out")"
[ -n "$drawn" ] && [ "$drawn" -gt 0 ] && [ "$drawn" -lt 5103 ] && ok ||
  bad "--foliage adaptive from 1.5 framing distances drew '$drawn' of 5103 leaves"
if command -v node >/dev/null; then
  read -r n_ad g_ad < <(node "$pixels" "$tmp/adaptive.png")
  [ "$g_ad" -gt 100 ] && ok || bad "--foliage adaptive: $g_ad leaf-green pixels"
fi
# the same cut on Vulkan: a compute pass before the render pass, one indirect draw inside it
expect 0 "render per-leaf LOD on Vulkan" -- "$XYLEM" render --backend vulkan --foliage adaptive --camera 30,20,1.5 --size 96x96 --out "$tmp/vadaptive.png"
vdrawn="$(sed -n 's/.* \([0-9]*\) of 5103 leaves drawn.*/\1/p' "$tmp/out")"
[ "$vdrawn" = "$drawn" ] && ok ||
  bad "--foliage adaptive drew '$vdrawn' leaves on Vulkan, '$drawn' on GL"
expect 0 "render a leafless preset" -- "$XYLEM" render --preset abop-1.24a --size 32x32 --out "$tmp/nl.png"
grep -q "^leaves:" "$tmp/out" && bad "a leafless tree reported leaves" || ok
expect 64 "render bad --foliage" -- "$XYLEM" render --foliage sprites --out "$tmp/x.png"
contains "takes full, lod, adaptive, none, billboard or impostor" "bad --foliage names the values"
# the tree as its billboard: baked from the tree, drawn in its place
for kind in spherical cylindrical cross; do
  expect 0 "render --foliage billboard --billboard $kind" -- "$XYLEM" render --foliage billboard --billboard $kind --billboard-size 64 --size 64x64 --out "$tmp/bb_$kind.png"
  contains "billboard: $kind" "billboard $kind named"
done
contains "4 views of 64 x 64 texels" "a cross has 4 planes by default"
cmp -s "$tmp/bb_cross.png" "$tmp/bb_spherical.png" && bad "cross and spherical billboards look the same" || ok
expect 0 "render a 3-plane cross with its image error" -- "$XYLEM" render --foliage billboard --planes 3 --billboard-size 32 --billboard-error --size 32x32 --out "$tmp/bb3.png"
contains "3 views of 32 x 32 texels" "--planes 3 bakes three views"
contains "20 dodecahedron views" "--billboard-error prints the table"
contains "mean " "--billboard-error prints the mean"
# the octahedral impostor: grid^2 views in one atlas
expect 0 "render --foliage impostor" -- "$XYLEM" render --foliage impostor --grid 3 --billboard-size 32 --size 32x32 --out "$tmp/imp.png"
contains "billboard: octahedral" "the impostor is the octahedral billboard"
contains "9 views of 32 x 32 texels" "--grid 3 bakes 3 x 3 views"
expect 0 "render --billboard octahedral" -- "$XYLEM" render --foliage billboard --billboard octahedral --billboard-size 16 --size 32x32 --out "$tmp/oct.png"
contains "64 views of 16 x 16 texels" "the grid is 8 x 8 by default"
expect 64 "--grid 1" -- "$XYLEM" render --foliage impostor --grid 1 --out "$tmp/x.png"
contains "--grid takes a whole number from 2 to 32" "a bad grid is named"
expect 64 "--grid 33" -- "$XYLEM" render --foliage impostor --grid 33 --out "$tmp/x.png"
expect 64 "--grid on a cross" -- "$XYLEM" render --foliage billboard --grid 4 --out "$tmp/x.png"
contains "--grid is the octahedral billboard's" "--grid on another kind is refused"
expect 64 "--foliage impostor with another kind" -- "$XYLEM" render --foliage impostor --billboard cross --out "$tmp/x.png"
expect 64 "an atlas over the limit" -- "$XYLEM" render --foliage impostor --grid 32 --billboard-size 1024 --out "$tmp/x.png"
contains "atlas" "an atlas over the limit is named"
expect 64 "billboard with 1 plane" -- "$XYLEM" render --foliage billboard --planes 1 --out "$tmp/x.png"
expect 64 "billboard with 9 planes" -- "$XYLEM" render --foliage billboard --planes 9 --out "$tmp/x.png"
expect 64 "billboard of absurd resolution" -- "$XYLEM" render --foliage billboard --billboard-size 100000 --out "$tmp/x.png"
contains "--billboard-size takes" "a bad billboard size is named"
expect 64 "bad billboard kind" -- "$XYLEM" render --foliage billboard --billboard sprite --out "$tmp/x.png"
expect 64 "--planes on a spherical billboard" -- "$XYLEM" render --foliage billboard --billboard spherical --planes 3 --out "$tmp/x.png"
expect 64 "--billboard without --foliage billboard" -- "$XYLEM" render --billboard cross --out "$tmp/x.png"
# the same billboards baked and drawn on Vulkan: GL's pictures within 6 levels RMSE (measured
# 2.99 to 3.91 at this size; GL's and Vulkan's whole tree differ by 14.2, two kinds by 31.6)
for kind in spherical cylindrical cross; do
  expect 0 "render --backend vulkan --billboard $kind" -- "$XYLEM" render --backend vulkan --foliage billboard --billboard $kind --billboard-size 64 --size 64x64 --out "$tmp/vbb_$kind.png"
  contains "billboard: $kind" "Vulkan billboard $kind named"
  contains "(Vulkan)" "Vulkan billboard $kind on Vulkan"
  if command -v node >/dev/null; then
    read -r _ _ _ rmse_bb < <(node "$pixels" --diff "$tmp/bb_$kind.png" "$tmp/vbb_$kind.png")
    awk -v r="$rmse_bb" 'BEGIN { exit !(r <= 6) }' && ok ||
      bad "$kind billboard, GL against Vulkan: RMSE $rmse_bb"
  fi
done
expect 0 "render --foliage impostor on Vulkan" -- "$XYLEM" render --backend vulkan --foliage impostor --grid 3 --billboard-size 32 --size 32x32 --out "$tmp/vimp.png"
contains "billboard: octahedral" "the Vulkan impostor is the octahedral billboard"
contains "9 views of 32 x 32 texels" "a 3-grid Vulkan impostor bakes 9 views"
expect 64 "--billboard-error on Vulkan" -- "$XYLEM" render --backend vulkan --foliage billboard --billboard-error --out "$tmp/x.png"
contains "--billboard-error renders with the GL backend only" "--billboard-error on Vulkan is refused"
[ ! -e "$tmp/x.png" ] && ok || bad "a refused billboard render left x.png"
# a forest of the tree: N instances on a grid, per-instance leaf levels (GL only)
expect 0 "render --forest 9" -- "$XYLEM" render --forest 9 --size 64x48 --out "$tmp/forest9.png"
contains "forest: 9 trees (16 bytes each)" "--forest prints the trees and bytes per instance"
contains "forest frame: " "--forest prints the frame time"
contains " draws, " "--forest prints the draws"
contains " leaves, " "--forest prints the leaves drawn"
contains " triangles" "--forest prints the triangles drawn"
expect 0 "render --forest 4 --foliage billboard" -- "$XYLEM" render --forest 4 --foliage billboard --billboard-size 32 --size 64x48 --camera 10,20,40 --error-px 4 --out "$tmp/forest4.png"
contains "billboard " "a far forest draws billboards"
expect 64 "--forest 0" -- "$XYLEM" render --forest 0 --out "$tmp/x.png"
contains "--forest takes" "a bad forest size is named"
expect 64 "--forest of absurd size" -- "$XYLEM" render --forest 100000000000 --out "$tmp/x.png"
expect 64 "--forest on Vulkan" -- "$XYLEM" render --backend vulkan --forest 4 --out "$tmp/x.png"
expect 64 "--forest with --foliage none" -- "$XYLEM" render --foliage none --forest 4 --out "$tmp/x.png"
expect 0 "render --forest 4 --foliage impostor" -- "$XYLEM" render --forest 4 --foliage impostor --billboard-size 32 --grid 4 --size 64x48 --camera 10,20,40 --error-px 4 --out "$tmp/forest4i.png"
contains "impostor " "a far forest draws octahedral impostors"
contains " cross-fading" "--forest prints the instances cross-fading"
expect 0 "render --forest 4 --foliage adaptive" -- "$XYLEM" render --forest 4 --foliage adaptive --size 64x48 --out "$tmp/forest4a.png"
contains "4 with a per-leaf cut" "--foliage adaptive gives the nearest trees a cut of their own"
expect 64 "--fade out of range" -- "$XYLEM" render --forest 4 --fade 5 --out "$tmp/x.png"
contains "--fade takes" "a bad fade is named"
expect 64 "--fade without a forest" -- "$XYLEM" render --fade 0.5 --out "$tmp/x.png"
[ ! -e "$tmp/x.png" ] && ok || bad "a refused forest render left x.png"
expect 64 "render --foliage without a value" -- "$XYLEM" render --out "$tmp/x.png" --foliage
expect 64 "--foliage is not view's" -- "$XYLEM" view --foliage
expect 64 "render bad camera distance" -- "$XYLEM" render --camera 10,10,0 --out "$tmp/x.png"
expect 0 "render leaves on Vulkan" -- "$XYLEM" render --backend vulkan --size 96x96 --out "$tmp/vleafy.png"
contains "(Vulkan)" "Vulkan device named with leaves"
contains "leaves: --foliage lod: LOD " "Vulkan names the leaf LOD"
grep -q "draw leaves yet" "$tmp/out" && bad "Vulkan still says it draws no leaves" || ok
expect 0 "render bare stems on Vulkan" -- "$XYLEM" render --backend vulkan --foliage none --size 96x96 --out "$tmp/vbare.png"
if command -v node >/dev/null; then
  read -r n_vleafy g_vleafy < <(node "$pixels" "$tmp/vleafy.png")
  read -r n_vbare g_vbare < <(node "$pixels" "$tmp/vbare.png")
  [ "$n_vleafy" -eq 9216 ] && [ "$g_vleafy" -gt 500 ] && [ "$g_vbare" -eq 0 ] && ok ||
    bad "Vulkan leaf-green pixels: $g_vleafy of $n_vleafy with leaves, $g_vbare without"
  # GL and Vulkan draw the same leaves: their leaf-green counts agree within 5 %, and with the
  # leaves the two pictures differ no more (RMSE) than the bare stems' do, edges and MSAA alone
  [ $((20 * (g_vleafy > g_leafy ? g_vleafy - g_leafy : g_leafy - g_vleafy))) -le "$g_leafy" ] && ok ||
    bad "leaf-green pixels: $g_leafy on GL, $g_vleafy on Vulkan"
  read -r _ _ _ rmse_leafy < <(node "$pixels" --diff "$tmp/leafy.png" "$tmp/vleafy.png")
  read -r _ _ _ rmse_bare < <(node "$pixels" --diff "$tmp/bare.png" "$tmp/vbare.png")
  awk -v l="$rmse_leafy" -v b="$rmse_bare" 'BEGIN { exit !(l <= b) }' && ok ||
    bad "GL against Vulkan: RMSE $rmse_leafy with leaves, $rmse_bare for the bare stems"
fi
expect 0 "render leaves on Vulkan, no MSAA, wireframe" -- "$XYLEM" render --backend vulkan --samples 1 --wireframe --camera 40,20,0.5 --size 64x64 --out "$tmp/vl1.png"
# view: the same in a GLFW window, on an X server of its own (Xvfb)
expect 64 "view writes no --out" -- "$XYLEM" view --out "$tmp/x.png"
expect 64 "view screenshot needs --frames" -- "$XYLEM" view --screenshot "$tmp/x.png"
expect 64 "view is GL only" -- "$XYLEM" view --backend vulkan
expect 64 "view has no cpu path" -- "$XYLEM" view --tess cpu
expect 69 "view without a display" -- env -u DISPLAY -u WAYLAND_DISPLAY "$XYLEM" view --frames 1
contains "no window system" "view says why"
expect 0 "view two frames, screenshot" -- xview "$XYLEM" view --frames 2 --size 80x60 --tess hardware --wireframe --screenshot "$tmp/view.png"
contains "GLFW window" "view names the window"
png_magic "$tmp/view.png" && passed=$((passed + 1)) || { failed=$((failed + 1)); echo "FAIL: view wrote no PNG"; }

# view's tuning panel (Dear ImGui): only in a build with libimgui-dev; without it the fixed viewer
# says so and --set is refused
if [ "${XYL_CLI_PANEL:-0}" != 1 ]; then
  expect 0 "view without the panel" -- xview "$XYLEM" view --frames 1 --size 64x48
  contains "built without Dear ImGui" "view says it has no panel"
  expect 69 "--set needs the panel" -- "$XYLEM" view --set sides=6
  contains "libimgui-dev" "--set says what is missing"
else
  region() { python3 "$data/../png_region.py" "$@"; }
  bg=0.86,0.90,0.95
  # two trees from different --set values: the tree's half differs, the panel's half is drawn
  expect 0 "view panel, one tree" -- xview "$XYLEM" view --frames 2 --size 480x360 --set depth=3 --set angle=20 --screenshot "$tmp/p1.png"
  contains "tuning panel" "view names the panel"
  expect 0 "view panel, another tree" -- xview "$XYLEM" view --frames 2 --size 480x360 --set depth=4 --set angle=35 --set sides=8 --screenshot "$tmp/p2.png"
  read -r n total < <(region differ "$tmp/p1.png" "$tmp/p2.png" 240 0 480 360)
  [ "$n" -gt 500 ] && ok || bad "different --set values drew the same tree ($n of $total pixels differ)"
  read -r n total < <(region not-colour "$tmp/p1.png" 0 0 240 360 "$bg")
  [ "$n" -gt $((total * 9 / 10)) ] && ok || bad "no panel drawn ($n of $total pixels are not the background)"
  expect 0 "view with the panel hidden" -- xview "$XYLEM" view --frames 2 --size 480x360 --set depth=3 --set angle=20 --set panel=0 --screenshot "$tmp/p0.png"
  read -r n total < <(region not-colour "$tmp/p0.png" 0 0 60 360 "$bg")
  [ "$n" -eq 0 ] && ok || bad "panel=0 still draws a panel ($n of $total pixels)"

  # only the stages below a change regrow
  expect 0 "view regrows stage by stage" -- xview "$XYLEM" view --frames 1 --size 320x240 --set leaves=0 --set sides=6 --set level=3 --set depth=3 --set variant=circle --set leaves=1 --set root_flare=2 --set base=open --set error_world=0.5
  grep -q '^sides=6: regrew stems [0-9.]* ms, patches [0-9.]* ms$' "$tmp/out" && ok || bad "sides regrows stems and patches only"
  contains "level=3: regrew nothing" "a level regrows nothing"
  grep -q '^depth=3: regrew derive .*, turtle .*, stems .*, patches [0-9.]* ms$' "$tmp/out" && ok || bad "depth does not parse again"
  grep -q '^variant=circle: regrew patches [0-9.]* ms$' "$tmp/out" && ok || bad "the handle rule rebuilds the patches only"
  grep -q '^leaves=1: regrew foliage [0-9.]* ms$' "$tmp/out" && ok || bad "leaves grow on the kept skeleton"
  grep -q '^root_flare=2: regrew stems [0-9.]* ms, patches [0-9.]* ms$' "$tmp/out" && ok || bad "root_flare regrows stems and patches only"
  grep -q '^base=open: regrew stems [0-9.]* ms, patches [0-9.]* ms$' "$tmp/out" && ok || bad "base regrows stems and patches only"
  grep -q '^error_world=0.5: regrew stems [0-9.]* ms, patches [0-9.]* ms$' "$tmp/out" && ok || bad "error_world regrows stems and patches only"

  # a scripted sequence ends with the tree the CLI builds from the same parameters
  expect 0 "view --set sequence, exports" -- xview "$XYLEM" view --preset abop-2.6-monopodial --frames 1 --size 320x240 --set leaves=0 --set depth=7 --set sides=3 --set define.r2=0.7 --set angle=30 --set tropism=0,-1,0,0.2 --set sides=6 --set radius_exponent=2.5 --set subdivide=catmark --set root_flare=1.5 --set export="$tmp/s.lsys" --set export="$tmp/s.skel" --set export="$tmp/s.glb" --set export="$tmp/s.png"
  grep -q '^#define r2 0.7 ' "$tmp/s.lsys" && grep -q '^#depth 7' "$tmp/s.lsys" && grep -q '^#angle 30' "$tmp/s.lsys" && grep -q '^#tropism 0 -1 0 0.2' "$tmp/s.lsys" && ok || bad "the .lsys lacks the tuned values"
  expect 0 "CLI skeleton of the tuned grammar" -- "$XYLEM" skeleton --grammar "$tmp/s.lsys" --radius-exponent 2.5 --out "$tmp/c.skel"
  cmp -s "$tmp/s.skel" "$tmp/c.skel" && ok || bad "the viewer's skeleton differs from the CLI's"
  expect 0 "CLI mesh of the tuned grammar" -- "$XYLEM" mesh --grammar "$tmp/s.lsys" --radius-exponent 2.5 --sides 6 --subdivide catmark --root-flare 1.5 --out "$tmp/c.glb"
  cmp -s "$tmp/s.glb" "$tmp/c.glb" && ok || bad "the viewer's mesh differs from the CLI's"
  png_magic "$tmp/s.png" && ok || bad "export=FILE.png wrote no PNG"
  expect 0 "view exports leaves with the stems" -- xview "$XYLEM" view --preset abop-2.8-ternary --frames 1 --size 320x240 --set depth=4 --set leaves=1 --set leaf_aspect=0.3 --set export="$tmp/l.glb"
  expect 0 "CLI stems and leaves" -- "$XYLEM" mesh --preset abop-2.8-ternary --depth 4 --foliage --aspect 0.3 --out "$tmp/cl.glb"
  cmp -s "$tmp/l.glb" "$tmp/cl.glb" && ok || bad "the viewer's leaves differ from the CLI's"

  # leaves in the window: with them the tree's half differs from the stems alone and has
  # leaf-green pixels (png_pixels.mjs), the stems alone have none, in the window and in a PNG export
  expect 0 "view draws the leaves" -- xview "$XYLEM" view --frames 2 --size 480x360 --set depth=5 --set leaves=1 --set export="$tmp/vle.png" --screenshot "$tmp/vl1.png"
  contains "leaves: foliage=lod: LOD " "view names the leaf LOD drawn"
  expect 0 "view with the leaves built, not drawn" -- xview "$XYLEM" view --frames 2 --size 480x360 --set depth=5 --set leaves=1 --set foliage=none --set export="$tmp/vl0e.png" --screenshot "$tmp/vl0.png"
  contains "leaves: not drawn (foliage=none); the budget picks LOD" "foliage=none says the leaves are not drawn"
  read -r n total < <(region differ "$tmp/vl1.png" "$tmp/vl0.png" 240 0 480 360)
  [ "$n" -gt 2000 ] && ok || bad "leaves changed only $n of $total pixels of the tree's half"
  if command -v node >/dev/null; then
    read -r _ g1 < <(node "$pixels" "$tmp/vl1.png")
    read -r _ g0 < <(node "$pixels" "$tmp/vl0.png")
    read -r _ ge1 < <(node "$pixels" "$tmp/vle.png")
    read -r _ ge0 < <(node "$pixels" "$tmp/vl0e.png")
    [ "$g1" -gt 2000 ] && [ "$g0" -eq 0 ] && [ "$ge1" -gt 2000 ] && [ "$ge0" -eq 0 ] && ok ||
      bad "leaf-green pixels: window $g1 with leaves, $g0 without; export $ge1 with, $ge0 without"
  else
    bad "node (scripts/setup.sh installs it) is needed to read the viewer's leaves back"
  fi
  # wireframe draws the stems' edges; the leaves stay solid
  expect 0 "view leaves in wireframe" -- xview "$XYLEM" view --frames 1 --size 320x240 --set depth=5 --set foliage=lod --set wireframe=1 --set panel=0 --screenshot "$tmp/vlw.png"
  if command -v node >/dev/null; then
    read -r _ gw < <(node "$pixels" "$tmp/vlw.png")
    [ "$gw" -gt 1000 ] && ok || bad "wireframe lost the leaves ($gw leaf-green pixels)"
  fi
  # the leaves drawn are those render --foliage lod picks for the same size, camera and budget:
  # both frame stems and leaves from the same box and pick with xyl_foliage_pick
  for view in "30,10 0.5 96x96" "40,20 8 320x240" "-60,35 2 200x300"; do
    read -r cam px size <<<"$view"
    expect 0 "view leaves at $view" -- xview "$XYLEM" view --frames 1 --size "$size" --camera "$cam" --error-px "$px" --set panel=0 --set foliage=lod
    v=$(grep -o '[0-9]* of [0-9]* leaves drawn' "$tmp/out")
    expect 0 "render leaves at $view" -- "$XYLEM" render --size "$size" --camera "$cam" --error-px "$px" --out "$tmp/vr.png"
    r=$(grep -o '[0-9]* of [0-9]* leaves drawn' "$tmp/out")
    [ -n "$v" ] && [ "$v" = "$r" ] && ok || bad "view drew '$v', render '$r' at $view (camera, px, size)"
  done
  expect 0 "view all leaves" -- xview "$XYLEM" view --frames 1 --size 96x96 --set foliage=full
  contains "leaves: foliage=full: LOD 0 of 0..5102, 5103 of 5103 leaves drawn in the last frame" "foliage=full draws every leaf"
  expect 0 "view of a leafless tree with leaves on" -- xview "$XYLEM" view --preset abop-1.24a --frames 1 --size 64x48 --set leaves=1
  grep -q "^leaves:" "$tmp/out" && bad "a leafless tree reported leaves" || ok
  expect 64 "--set foliage bad value" -- "$XYLEM" view --set foliage=billboard
  contains "foliage takes lod, full or none" "--set foliage names the values"

  # a bad grammar shows its error; the last good tree stays on screen and in the exports
  expect 65 "view keeps the last good tree" -- xview "$XYLEM" view --frames 2 --size 480x360 --set depth=3 --set export="$tmp/good.glb" --set grammar_text=$'#depth 3\naxiom: F\np1: F -> F[+F' --set export="$tmp/after.glb" --screenshot "$tmp/pb.png"
  contains "grammar_text: grammar:3:11: invalid grammar: '[' is never closed (the last good tree stays)" "the grammar error at its line"
  cmp -s "$tmp/good.glb" "$tmp/after.glb" && ok || bad "a bad grammar replaced the tree"
  read -r m total < <(region not-colour "$tmp/pb.png" 240 0 480 360 "$bg")
  [ "$m" -gt 500 ] && ok || bad "no tree on screen after a bad grammar"

  printf 'axiom: F\np1: F -> F[+F\n' >"$tmp/bad.lsys"
  expect 65 "view of a grammar that does not parse" -- xview "$XYLEM" view --grammar "$tmp/bad.lsys" --frames 1 --size 64x48
  contains "bad.lsys: grammar:2:11: invalid grammar: '[' is never closed (no tree yet)" "the first tree's error"
  expect 65 "view stops a runaway depth" -- xview "$XYLEM" view --frames 1 --size 64x48 --set depth=14
  contains "depth=14: derive: limit exceeded" "the limit is shown, the tree stays"

  expect 64 "--set unknown name" -- "$XYLEM" view --set bogus=1
  contains "unknown name 'bogus'" "--set names the bad name"
  expect 64 "--set without =" -- "$XYLEM" view --set sides
  expect 64 "--set bad value, before any window" -- env -u DISPLAY -u WAYLAND_DISPLAY "$XYLEM" view --set sides=99
  contains "sides takes a whole number 3..32" "--set says the range"
  expect 64 "--set unknown define" -- "$XYLEM" view --set define.nope=1
  expect 0 "--set define of the grammar set just before" -- xview "$XYLEM" view --frames 1 --size 64x48 --set preset=abop-2.6-monopodial --set define.r2=0.5
  expect 64 "--set export needs a known type" -- "$XYLEM" view --set export="$tmp/x.txt"
  expect 64 "--set tropism needs four numbers" -- "$XYLEM" view --set tropism=0,1
  expect 66 "--set grammar file missing" -- "$XYLEM" view --set grammar="$tmp/none.lsys"
  expect 73 "--set export unwritable" -- xview "$XYLEM" view --frames 1 --size 64x48 --set export="$tmp/no/dir/x.glb"
  expect 64 "--set is view's" -- "$XYLEM" render --set sides=4 --out "$tmp/x.png"
  expect 64 "--set tunes a grammar only" -- "$XYLEM" view --mesh "$tmp/tree.glb" --set sides=4
fi

echo "test_cli: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
