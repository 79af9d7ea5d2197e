#!/usr/bin/env node
// Validates glTF 2.0 files (.glb or .gltf) with the Khronos glTF validator and exits
// non-zero when any file has errors, so tests and CI can gate on it.
//
//   node tools/gltf-validator/validate.js [--strict] FILE...
//
// Prints one summary line per file and one line per issue (code, severity, JSON pointer,
// message). Exit status: 0 no errors (warnings, infos and hints are printed, not fatal
// unless --strict), 1 errors (or warnings with --strict), 2 bad usage or unreadable file.
'use strict';

const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

const SEVERITY = ['error', 'warning', 'info', 'hint'];

async function validateFile(file, strict) {
  let bytes;
  try {
    bytes = fs.readFileSync(file);
  } catch (e) {
    console.error(`${file}: cannot read: ${e.message}`);
    return 2;
  }
  let report;
  try {
    report = await validator.validateBytes(new Uint8Array(bytes), {
      uri: path.basename(file),
      maxIssues: 0, // report every issue
      externalResourceFunction: (uri) =>
        Promise.reject(`external resource ${uri}: weft writes self-contained .glb files`),
    });
  } catch (e) {
    console.error(`${file}: the validator could not read it: ${e}`);
    return 1;
  }
  const issues = report.issues;
  console.log(
    `${file}: ${issues.numErrors} errors, ${issues.numWarnings} warnings, ` +
      `${issues.numInfos} infos, ${issues.numHints} hints ` +
      `(glTF validator ${report.validatorVersion})`
  );
  for (const m of issues.messages) {
    const where = m.pointer !== undefined ? m.pointer : `byte ${m.offset}`;
    console.log(`  ${SEVERITY[m.severity] || m.severity} ${m.code} at ${where}: ${m.message}`);
  }
  if (issues.numErrors > 0 || (strict && issues.numWarnings > 0)) {
    return 1;
  }
  return 0;
}

async function main(argv) {
  const strict = argv.includes('--strict');
  const files = argv.filter((a) => a !== '--strict');
  if (files.length === 0 || files.some((f) => f.startsWith('-'))) {
    console.error('usage: node validate.js [--strict] FILE.glb...');
    return 2;
  }
  let status = 0;
  for (const file of files) {
    status = Math.max(status, await validateFile(file, strict));
  }
  return status;
}

main(process.argv.slice(2)).then((code) => process.exit(code));
