// Validates glTF files with the Khronos glTF validator (npm `gltf-validator`, which tools/test.sh
// installs under target/gltf-validator); prints one JSON line per file, exits 1 on any error.
//   node tools/gltf-validate.js FILE...
const fs = require('fs');
const path = require('path');
const validator = require(process.env.GLTF_VALIDATOR_MODULE || 'gltf-validator');
(async () => {
  let failed = false;
  for (const file of process.argv.slice(2)) {
    const data = new Uint8Array(fs.readFileSync(file));
    const report = await validator.validateBytes(data, {
      uri: path.basename(file),
      externalResourceFunction: (uri) => Promise.reject(new Error('external resource: ' + uri)),
    });
    const issues = report.issues;
    console.log(JSON.stringify({ file, errors: issues.numErrors, warnings: issues.numWarnings,
      infos: issues.numInfos, messages: issues.messages.slice(0, 10) }));
    if (issues.numErrors > 0) failed = true;
  }
  process.exit(failed ? 1 : 0);
})();
