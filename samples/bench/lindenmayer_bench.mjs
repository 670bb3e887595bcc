// Peer benchmark for samples/bench/bench_lsystem.c: derives a deterministic, non-parametric L-system with
// the npm package `lindenmayer` and prints one parseable line.
//
//   node lindenmayer_bench.mjs <axiom> <depth> <repeats> <pred>=<successor> [...]
//   node lindenmayer_bench.mjs F 8 7 'F=F[+F]F[-F]F'
//
// Output (one line, key=value, on stdout):
//   lindenmayer version=1.5.4 node=v20.x depth=8 repeats=7 batch=1 modules=976561
//     median_ns=... min_ns=... fnv1a32=0x........
// median_ns and min_ns are per derivation; fnv1a32 hashes the derived string's characters.
//
// Only setAxiom() + iterate() are timed. iterate()'s string is left as V8 builds it (possibly a
// rope); its length and hash are taken afterwards, outside the timed region, so the peer is not
// charged for flattening it. Warm-up and batching are described in main(). On a bad argument or
// a missing package it prints "lindenmayer: error: ..." and exits 2.
import { createRequire } from 'node:module';

function fail(message) {
  console.log(`lindenmayer: error: ${message}`);
  process.exit(2);
}

function parseArgs(argv) {
  if (argv.length < 4) {
    fail('usage: lindenmayer_bench.mjs <axiom> <depth> <repeats> <pred>=<successor>...');
  }
  const [axiom, depthText, repeatsText, ...ruleTexts] = argv;
  const depth = Number.parseInt(depthText, 10);
  const repeats = Number.parseInt(repeatsText, 10);
  if (!(depth >= 0 && depth <= 64)) fail(`depth out of range: ${depthText}`);
  if (!(repeats >= 1 && repeats <= 1000)) fail(`repeats out of range: ${repeatsText}`);
  const productions = {};
  for (const text of ruleTexts) {
    const eq = text.indexOf('=');
    if (eq !== 1) fail(`a rule is <one symbol>=<successor>, got: ${text}`);
    productions[text[0]] = text.slice(2);
  }
  return { axiom, depth, repeats, productions };
}

// FNV-1a, 32 bits, over the UTF-16 code units (the grammars here are ASCII, so bytes).
function fnv1a32(s) {
  let h = 0x811c9dc5;
  for (let i = 0; i < s.length; ++i) {
    h ^= s.charCodeAt(i);
    h = Math.imul(h, 0x01000193);
  }
  return h >>> 0;
}

// The system is built once (as xylem's grammar is parsed once); a run resets the axiom and
// iterates, which is what xyl_lsystem_derive does.
function derive(ls, cfg) {
  ls.setAxiom(cfg.axiom);
  return ls.iterate(cfg.depth);
}

async function main() {
  const cfg = parseArgs(process.argv.slice(2));
  let LSystem;
  let version = 'unknown';
  try {
    LSystem = (await import('lindenmayer')).default;
    version = createRequire(import.meta.url)('lindenmayer/package.json').version;
  } catch (e) {
    fail(`cannot load the package (npm ci in samples/bench): ${e.message.split('\n')[0]}`);
  }

  // Warm-up (untimed): at least 3 runs and 200 ms, so that small cases are measured with
  // optimised code; it also gives the time of one run, from which the batch size follows.
  const ls = new LSystem({ axiom: cfg.axiom, productions: cfg.productions });
  let result;
  let runs = 0;
  const w0 = process.hrtime.bigint();
  let warm = 0;
  while (runs < 3 || (warm < 200e6 && runs < 10000)) {
    result = derive(ls, cfg);
    ++runs;
    warm = Number(process.hrtime.bigint() - w0);
  }
  // Like bench_lsystem: a sample of a fast case runs it back to back for at least 5 ms.
  const batch = Math.min(100000, Math.max(1, Math.ceil(5e6 / (warm / runs))));
  const times = [];
  for (let r = 0; r < cfg.repeats; ++r) {
    const t0 = process.hrtime.bigint();
    for (let b = 0; b < batch; ++b) result = derive(ls, cfg);
    const t1 = process.hrtime.bigint();
    times.push(Number(t1 - t0) / batch);
  }
  if (cfg.depth === 0) result = cfg.axiom;
  if (typeof result !== 'string') fail('iterate() did not return a string');
  times.sort((a, b) => a - b);
  const mid = times.length >> 1;
  const median = times.length % 2 ? times[mid] : (times[mid - 1] + times[mid]) / 2;
  const hash = fnv1a32(result).toString(16).padStart(8, '0');
  console.log(
    `lindenmayer version=${version} node=${process.version} depth=${cfg.depth} ` +
      `repeats=${cfg.repeats} batch=${batch} modules=${result.length} ` +
      `median_ns=${Math.round(median)} min_ns=${Math.round(times[0])} ` +
      `fnv1a32=0x${hash}`,
  );
}

main().catch((e) => fail(e.message.split('\n')[0]));
