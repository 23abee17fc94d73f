// node validate.mjs FILE.glb...
// Runs the Khronos glTF-Validator (npm gltf-validator) on each file and prints one JSON line per
// file: {"file", "errors", "warnings", "infos", "hints", "messages": [{code, severity, message, pointer}]}.
// Exit 0 when every file was read (the caller judges the counts), 2 on a set-up problem.
import { readFileSync } from 'node:fs';
import { createRequire } from 'node:module';

const require = createRequire(import.meta.url);
const validator = require('gltf-validator');

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error('usage: node validate.mjs FILE.glb...');
  process.exit(2);
}
for (const file of files) {
  const bytes = new Uint8Array(readFileSync(file));
  const report = await validator.validateBytes(bytes, {
    uri: file,
    maxIssues: 100,
    externalResourceFunction: (uri) => Promise.reject(new Error(`no external resources: ${uri}`)),
  });
  const i = report.issues;
  console.log(JSON.stringify({
    file,
    validator: report.validatorVersion,
    errors: i.numErrors,
    warnings: i.numWarnings,
    infos: i.numInfos,
    hints: i.numHints,
    messages: i.messages.map((m) => ({ code: m.code, severity: m.severity, message: m.message, pointer: m.pointer })),
  }));
}
