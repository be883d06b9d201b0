#!/usr/bin/env node
// Runs the Khronos glTF validator (npm gltf-validator) on .glb files and fails on any error or
// warning; infos and hints are printed but allowed.
//   node validate_gltf.js FILE.glb...
// Prints every issue, one line per file, and "N passed, M failed"; exit 0 only when all pass.
'use strict';

const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

async function main() {
  const files = process.argv.slice(2);
  if (!files.length) throw new Error('usage: validate_gltf.js FILE.glb...');
  let passed = 0;
  let failed = 0;
  console.log(`gltf-validator ${validator.version()}`);
  for (const file of files) {
    const bytes = new Uint8Array(fs.readFileSync(file));
    const report = await validator.validateBytes(bytes, {
      uri: path.basename(file),
      maxIssues: 0,
      externalResourceFunction: (uri) => Promise.reject(new Error(`external resource ${uri}: a .glb must be self-contained`)),
    });
    const {numErrors, numWarnings, numInfos, numHints, messages} = report.issues;
    for (const m of messages) console.log(`  ${['error', 'warning', 'info', 'hint'][m.severity]} ${m.code} ${m.pointer || ''}: ${m.message}`);
    const ok = numErrors === 0 && numWarnings === 0;
    if (ok) ++passed;
    else ++failed;
    console.log(`${ok ? 'PASS' : 'FAIL'} ${file}: ${numErrors} errors, ${numWarnings} warnings, ${numInfos} infos, ${numHints} hints`);
  }
  console.log(`${passed} passed, ${failed} failed`);
  process.exitCode = failed ? 1 : 0;
}

main().catch((err) => {
  console.error(err && err.stack ? err.stack : err);
  process.exitCode = 2;
});
