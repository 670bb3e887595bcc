// Peer for a future stem-meshing benchmark: generates trees with the npm package
// `@dgreenheck/ez-tree` (three.js geometry) under node, never rendering, and prints one parseable
// line per tree size. docs/peer-eztree.md records a run and explains the figures.
//
//   node eztree_bench.mjs [--repeats N] [--preset NAME|all] [--levels L] [--sections S]
//                         [--segments G] [--children C] [--step I] [--steps]
//   node eztree_bench.mjs                          # the built-in size ladder (see LADDER)
//   node eztree_bench.mjs --preset 'Oak Large'     # a preset of the package; 'all' for all 16
//   node eztree_bench.mjs --levels 3 --sections 20 --segments 16
//
// --step I runs only step I (from 0) of the ladder, and --steps loads the package, prints
// "eztree steps=N" (the ladder's length) and exits: bench_stems runs the ladder a step at a
// time, each in a node of its own, so that no node is left running while it measures its own
// tree.
// --preset and --levels may be repeated, one case each. A --levels case is the package's default
// options with branch.levels = L; --sections/--segments (every level) and --children (children of
// the trunk) modify all --levels cases. Without any case the ladder runs.
//
// Output (one line per case, key=value, on stdout):
//   eztree version=1.1.0 three=0.187.0 node=v20.x case=L3-s20-g16 branch_vertices=...
//     branch_triangles=... leaf_triangles=... median_ns=... min_ns=... repeats=7 batch=1
//     tubes=... boundary_edges=... welded_boundary_edges=... nonmanifold_edges=...
//     degenerate_triangles=... index_wrapped=...
// median_ns and min_ns are per tree. Triangles are index count / 3 of the branch and the leaf
// geometry (ez-tree keeps them in two meshes). The last six keys describe the branch mesh:
// tubes generated; edges used by one triangle, by index and after welding bit-equal positions;
// after welding, edges used by more than two triangles and triangles with two equal corners;
// indices >= 65536, which ez-tree's Uint16 index attribute wraps (the geometry three would draw
// is then not the one generated).
//
// Timed: new Tree(), options.copy(case), generate() -- what Tree.loadFromJson does. generate()
// grows the skeleton and builds both meshes in one call; nothing else is timed. On a bad argument
// or a package that cannot load it prints "eztree: error: ..." and exits 2.
import { createRequire } from 'node:module';
import { readFileSync } from 'node:fs';
import { dirname, join } from 'node:path';

function fail(message) {
  console.log(`eztree: error: ${message}`);
  process.exit(2);
}

// Sizes from about 10^3 to 10^6 branch triangles, inside the ranges of the package's own UI
// sliders (levels 0..3, trunk children 0..100, sections 1..20, segments 3..16).
const LADDER = [
  { levels: 1 },
  { levels: 2 },
  { levels: 3 },
  { levels: 3, sections: 20, segments: 16 },
  { levels: 3, sections: 20, segments: 16, children: 30 },
];

function parseCount(flag, text, lo, hi) {
  const v = Number(text);
  if (!Number.isInteger(v) || v < lo || v > hi) fail(`${flag} wants an integer in ${lo}..${hi}, got: ${text}`);
  return v;
}

function parseArgs(argv) {
  const cfg = { repeats: 7, presets: [], levels: [], mods: {}, step: undefined, steps: false };
  for (let i = 0; i < argv.length; ++i) {
    const flag = argv[i];
    if (flag === '--steps') {
      cfg.steps = true;
      continue;
    }
    const value = argv[i + 1];
    if (value === undefined) fail(`${flag} needs a value`);
    ++i;
    if (flag === '--repeats') cfg.repeats = parseCount(flag, value, 1, 1000);
    else if (flag === '--preset') cfg.presets.push(value);
    else if (flag === '--levels') cfg.levels.push(parseCount(flag, value, 0, 3));
    else if (flag === '--sections') cfg.mods.sections = parseCount(flag, value, 1, 1000);
    else if (flag === '--segments') cfg.mods.segments = parseCount(flag, value, 3, 1000);
    else if (flag === '--children') cfg.mods.children = parseCount(flag, value, 0, 10000);
    else if (flag === '--step') cfg.step = parseCount(flag, value, 0, LADDER.length - 1);
    else fail(`unknown option: ${flag}`);
  }
  return cfg;
}

// three's ImageLoader is reached at import time (ez-tree creates its bark and leaf textures from
// data: URIs in module scope). It calls document.createElementNS(xhtml, 'img'), adds 'load' and
// 'error' listeners and assigns src and fetchPriority. The stand-in image takes all that and never
// loads, so the textures stay empty; nothing else of the DOM is reached (window, self and
// __THREE_DEVTOOLS__ are only probed with typeof). Any other element fails loudly.
function installDocumentStandIn() {
  if (globalThis.document !== undefined) fail('a global document already exists');
  const stats = { images: 0 };
  globalThis.document = {
    createElementNS(ns, name) {
      if (name !== 'img') throw new Error(`stand-in document has no createElementNS('${name}')`);
      ++stats.images;
      return { addEventListener() {}, removeEventListener() {} };
    },
  };
  return stats;
}

function packageVersion(require, name) {
  // ez-tree's "exports" hides package.json; walk up from its entry point instead.
  let dir = dirname(require.resolve(name));
  for (let up = 0; up < 4; ++up, dir = dirname(dir)) {
    try {
      const pkg = JSON.parse(readFileSync(join(dir, 'package.json'), 'utf8'));
      if (pkg.name === name) return pkg.version;
    } catch {
      // no package.json at this level
    }
  }
  return 'unknown';
}

function levelsCase(levels, mods) {
  const spec = { branch: { levels } };
  let name = `L${levels}`;
  const perLevel = (v) => ({ 0: v, 1: v, 2: v, 3: v });
  if (mods.sections !== undefined) {
    spec.branch.sections = perLevel(mods.sections);
    name += `-s${mods.sections}`;
  }
  if (mods.segments !== undefined) {
    spec.branch.segments = perLevel(mods.segments);
    name += `-g${mods.segments}`;
  }
  if (mods.children !== undefined) {
    spec.branch.children = { 0: mods.children };
    name += `-c${mods.children}`;
  }
  return { name, spec };
}

function buildCases(cfg, TreePreset) {
  const cases = [];
  for (const wanted of cfg.presets) {
    const names = wanted === 'all' ? Object.keys(TreePreset) : [wanted.replaceAll('_', ' ')];
    for (const name of names) {
      if (!(name in TreePreset)) fail(`no preset '${wanted}'; presets: ${Object.keys(TreePreset).join(', ')}`);
      cases.push({ name: `preset:${name.replaceAll(' ', '_')}`, spec: structuredClone(TreePreset[name]) });
    }
  }
  for (const levels of cfg.levels) cases.push(levelsCase(levels, cfg.mods));
  if (cfg.step !== undefined) {
    if (cases.length) fail('--step runs a step of the ladder alone, without --preset or --levels');
    cases.push(levelsCase(LADDER[cfg.step].levels, LADDER[cfg.step]));
  } else if (cases.length === 0) {
    for (const step of LADDER) cases.push(levelsCase(step.levels, step));
  }
  return cases;
}

// Edge use counts from sorted edge keys; vertex ids stay below 2^26, so a key is exact in a double.
// Triangles with two equal (remapped) corners are counted apart and leave their edges out: after
// welding, a tube tapered to radius 0 (evergreen tips) ends in such slivers.
function edgeCounts(indices, remap) {
  const keys = new Float64Array(indices.length);
  let used = 0;
  let degenerate = 0;
  for (let t = 0; t < indices.length; t += 3) {
    const v = [remap[indices[t]], remap[indices[t + 1]], remap[indices[t + 2]]];
    if (v[0] === v[1] || v[1] === v[2] || v[2] === v[0]) {
      ++degenerate;
      continue;
    }
    for (let e = 0; e < 3; ++e) {
      const a = v[e];
      const b = v[(e + 1) % 3];
      keys[used++] = a < b ? a * 67108864 + b : b * 67108864 + a;
    }
  }
  const sorted = keys.subarray(0, used).sort();
  let boundary = 0;
  let nonmanifold = 0;
  for (let i = 0; i < sorted.length; ) {
    let j = i + 1;
    while (j < sorted.length && sorted[j] === sorted[i]) ++j;
    if (j - i === 1) ++boundary;
    else if (j - i > 2) ++nonmanifold;
    i = j;
  }
  return { boundary, nonmanifold, degenerate };
}

// Maps each vertex to the first vertex with a bit-equal position (+0 and -0 count as equal).
function weldByPosition(positions) {
  const n = positions.length / 3;
  const remap = new Uint32Array(n);
  const first = new Map();
  for (let v = 0; v < n; ++v) {
    const key = `${positions[3 * v]},${positions[3 * v + 1]},${positions[3 * v + 2]}`;
    const seen = first.get(key);
    remap[v] = seen === undefined ? v : seen;
    if (seen === undefined) first.set(key, v);
  }
  return remap;
}

// Geometry facts of one generated tree, measured outside the timed region.
function describe(Tree, spec) {
  const tree = new Tree();
  tree.options.copy(spec);
  let tubes = 0;
  const grow = tree.generateBranch;
  tree.generateBranch = function countTubes(branch) {
    ++tubes;
    return grow.call(this, branch);
  };
  tree.generate();
  const geo = tree.branchesMesh.geometry;
  const intended = tree.branches.indices; // the JS array before the Uint16Array copy
  const vertices = geo.getAttribute('position').count;
  const identity = new Uint32Array(vertices).map((_, i) => i);
  const byIndex = edgeCounts(intended, identity);
  const welded = edgeCounts(intended, weldByPosition(geo.getAttribute('position').array));
  let wrapped = 0;
  for (const i of intended) if (i > 65535) ++wrapped;
  return {
    vertices,
    triangles: geo.index.count / 3,
    leafTriangles: tree.leavesMesh.geometry.index.count / 3,
    tubes,
    boundary: byIndex.boundary,
    weldedBoundary: welded.boundary,
    nonmanifold: welded.nonmanifold,
    degenerate: welded.degenerate,
    wrapped,
  };
}

function makeTree(Tree, spec) {
  const tree = new Tree();
  tree.options.copy(spec);
  tree.generate();
  return tree;
}

function measure(Tree, spec, repeats) {
  // Warm-up (untimed): at least 3 trees and 200 ms, as lindenmayer_bench.mjs does; it also gives
  // the time of one tree, from which the batch follows (a sample lasts at least 5 ms).
  let runs = 0;
  let warm = 0;
  const w0 = process.hrtime.bigint();
  let keep;
  while (runs < 3 || (warm < 200e6 && runs < 10000)) {
    keep = makeTree(Tree, spec);
    ++runs;
    warm = Number(process.hrtime.bigint() - w0);
  }
  const batch = Math.min(10000, Math.max(1, Math.ceil(5e6 / (warm / runs))));
  const times = [];
  for (let r = 0; r < repeats; ++r) {
    const t0 = process.hrtime.bigint();
    for (let b = 0; b < batch; ++b) keep = makeTree(Tree, spec);
    const t1 = process.hrtime.bigint();
    times.push(Number(t1 - t0) / batch);
  }
  if (keep.branchesMesh.geometry.index === null) fail('generate() built no branch index');
  times.sort((a, b) => a - b);
  const mid = times.length >> 1;
  const median = times.length % 2 ? times[mid] : (times[mid - 1] + times[mid]) / 2;
  return { median, min: times[0], batch };
}

async function main() {
  const cfg = parseArgs(process.argv.slice(2));
  const stand = installDocumentStandIn();
  const require = createRequire(import.meta.url);
  let Tree;
  let TreePreset;
  let version;
  let threeVersion;
  try {
    ({ Tree, TreePreset } = await import('@dgreenheck/ez-tree'));
    version = packageVersion(require, '@dgreenheck/ez-tree');
    threeVersion = packageVersion(require, 'three');
  } catch (e) {
    fail(`cannot load the package (npm ci in samples/bench): ${e.message.split('\n')[0]}`);
  }
  if (cfg.steps) { // after loading the package, so that a caller learns that it cannot run
    console.log(`eztree steps=${LADDER.length}`);
    return;
  }
  const imagesAtImport = stand.images;
  for (const c of buildCases(cfg, TreePreset)) {
    const geo = describe(Tree, c.spec);
    const t = measure(Tree, c.spec, cfg.repeats);
    if (stand.images !== imagesAtImport) fail('generate() created images; the stand-in is not enough');
    console.log(
      `eztree version=${version} three=${threeVersion} node=${process.version} case=${c.name} ` +
        `branch_vertices=${geo.vertices} branch_triangles=${geo.triangles} ` +
        `leaf_triangles=${geo.leafTriangles} median_ns=${Math.round(t.median)} ` +
        `min_ns=${Math.round(t.min)} repeats=${cfg.repeats} batch=${t.batch} tubes=${geo.tubes} ` +
        `boundary_edges=${geo.boundary} welded_boundary_edges=${geo.weldedBoundary} ` +
        `nonmanifold_edges=${geo.nonmanifold} degenerate_triangles=${geo.degenerate} ` +
        `index_wrapped=${geo.wrapped}`,
    );
  }
}

main().catch((e) => fail(e.message.split('\n')[0]));
