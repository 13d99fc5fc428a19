// Validate .glb files with the Khronos glTF validator (npm `gltf-validator`, pinned in
// package.json): `node validate.mjs FILE.glb…` prints one JSON line per file with its numbers
// of errors, warnings, infos and hints and its messages (code, severity, pointer, message).
// Exits 1 if a file cannot be read or validated at all; the caller judges the counts.
import { readFile } from 'node:fs/promises';
import { createRequire } from 'node:module';

const require = createRequire(import.meta.url);
const validator = require('gltf-validator');

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error('usage: node validate.mjs FILE.glb…');
  process.exit(2);
}
let failed = false;
for (const file of files) {
  try {
    const bytes = new Uint8Array(await readFile(file));
    const report = await validator.validateBytes(bytes, {
      uri: file,
      maxIssues: 0, // report every issue
      // A .glb is self-contained: any external reference is itself an error.
      externalResourceFunction: (uri) => Promise.reject(`external resource ${uri}`),
    });
    const issues = report.issues;
    console.log(JSON.stringify({
      file,
      validatorVersion: report.validatorVersion,
      errors: issues.numErrors,
      warnings: issues.numWarnings,
      infos: issues.numInfos,
      hints: issues.numHints,
      messages: issues.messages.map((m) => ({
        code: m.code, severity: m.severity, pointer: m.pointer ?? null, message: m.message,
      })),
    }));
  } catch (e) {
    failed = true;
    console.log(JSON.stringify({ file, failure: String(e) }));
  }
}
process.exit(failed ? 1 : 0);
