// Runs the Khronos glTF-Validator on .glb files:
//
//   node tests/gltf/validate.mjs FILE.glb|FOLDER ...
//
// A folder stands for every .glb file in it (sorted by name), so any test can drop its files into
// one folder and have them all checked. For each file prints one summary line, then every message.
// Exit status: 0 when no file has an error or a warning (infos and hints are allowed), 1 when one
// does or a file cannot be read or no file was given, 2 when the gltf-validator package is not
// installed (scripts/setup.sh installs it with `npm ci` in tests/gltf).
import { readFileSync, readdirSync, statSync } from 'node:fs';
import { basename, join } from 'node:path';

const SEVERITY = ['error', 'warning', 'info', 'hint'];

async function loadValidator() {
  try {
    return await import('gltf-validator');
  } catch (e) {
    console.error('validate.mjs: the npm package gltf-validator is not installed ' +
                  `(${e.code || e.message}); run scripts/setup.sh or "npm ci" in tests/gltf`);
    process.exit(2);
  }
}

function expand(args) {
  const files = [];
  for (const arg of args) {
    if (statSync(arg, { throwIfNoEntry: false })?.isDirectory()) {
      const glbs = readdirSync(arg).filter((n) => n.endsWith('.glb')).sort();
      files.push(...glbs.map((n) => join(arg, n)));
    } else {
      files.push(arg);
    }
  }
  return files;
}

// Returns true when the file passes (no errors, no warnings).
async function check(validator, file) {
  let bytes;
  try {
    bytes = new Uint8Array(readFileSync(file));
  } catch (e) {
    console.log(`${file}: cannot read: ${e.message}`);
    return false;
  }
  let report;
  try {
    report = await validator.validateBytes(bytes, {
      uri: basename(file), format: 'glb', maxIssues: 0, writeTimestamp: false,
    });
  } catch (e) {
    console.log(`${file}: the validator refused it: ${e}`);
    return false;
  }
  const is = report.issues;
  console.log(`${file}: ${is.numErrors} errors, ${is.numWarnings} warnings, ` +
              `${is.numInfos} infos, ${is.numHints} hints`);
  for (const m of is.messages) {
    const where = m.pointer !== undefined ? m.pointer : `@${m.offset}`;
    console.log(`  ${SEVERITY[m.severity] || m.severity} ${m.code} ${where}: ${m.message}`);
  }
  return is.numErrors === 0 && is.numWarnings === 0;
}

const files = expand(process.argv.slice(2));
if (files.length === 0) {
  console.error('validate.mjs: no .glb file in the arguments (usage: validate.mjs FILE.glb|FOLDER ...)');
  process.exit(1);
}
const validator = await loadValidator();
console.log(`glTF-Validator ${validator.version()}: ${files.length} file(s)`);
let failed = 0;
for (const f of files) {
  if (!(await check(validator, f))) failed += 1;
}
console.log(`${files.length - failed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);
