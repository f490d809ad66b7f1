// The Khronos glTF-Validator (npm gltf-validator) over files named on the command line: one line
// per file with its error and warning counts, then each error's and warning's severity, code,
// message and JSON pointer.
// Exits 1 where any file has an error, 2 where a file cannot be read. The Rust tests run it on
// every glTF file they generate, so that they test glTF, not a dialect of raypipe's own.
//   node web/validate-gltf.mjs a.gltf b.glb ...
import fs from "node:fs";
import path from "node:path";
import validator from "gltf-validator";

let failed = false;
for (const file of process.argv.slice(2)) {
  let bytes;
  try {
    bytes = new Uint8Array(fs.readFileSync(file));
  } catch (error) {
    console.error(`${file}: ${error.message}`);
    process.exit(2);
  }
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    writeTimestamp: false,
    maxIssues: 0,
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        fs.readFile(path.join(path.dirname(file), decodeURIComponent(uri)), (error, data) =>
          error ? reject(error.message) : resolve(new Uint8Array(data)));
      }),
  });
  const { numErrors, numWarnings } = report.issues;
  console.log(`${file}: ${numErrors} errors, ${numWarnings} warnings`);
  for (const issue of report.issues.messages) {
    const severity = ["error", "warning"][issue.severity];
    if (severity) console.log(`  ${severity} ${issue.code}: ${issue.message} (${issue.pointer ?? ""})`);
  }
  failed ||= numErrors > 0;
}
process.exit(failed ? 1 : 0);
