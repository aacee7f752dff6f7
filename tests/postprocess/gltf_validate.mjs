// Runs the Khronos glTF validator (npm gltf-validator, installed by scripts/install-deps into
// .cache/gltf-validator) on .glb files: prints each file's messages, exits 1 when any file has an
// error or a warning, 2 on a usage or read problem.
//   node tests/postprocess/gltf_validate.mjs FILE.glb...
import { readFile } from "node:fs/promises";
import { createRequire } from "node:module";
import { dirname, join } from "node:path";
import { fileURLToPath } from "node:url";

const root = join(dirname(fileURLToPath(import.meta.url)), "..", "..");
const require = createRequire(join(root, ".cache", "gltf-validator", "package.json"));
const validator = require("gltf-validator");

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error("usage: node gltf_validate.mjs FILE.glb...");
  process.exit(2);
}
let bad = 0;
for (const file of files) {
  const bytes = new Uint8Array(await readFile(file));
  const report = await validator.validateBytes(bytes, { maxIssues: 100 });
  const { numErrors, numWarnings, numInfos, messages } = report.issues;
  console.log(`${file}: ${numErrors} errors, ${numWarnings} warnings, ${numInfos} infos`);
  for (const m of messages) console.log(`  [${m.severity}] ${m.code} ${m.pointer ?? ""}: ${m.message}`);
  if (numErrors > 0 || numWarnings > 0) ++bad;
}
process.exit(bad > 0 ? 1 : 0);
