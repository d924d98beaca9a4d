#!/usr/bin/env bash
# Builds the VS Code extension from its lockfile and packages it as
# editors/vscode/mcl.vsix: npm ci, type-check, bundle (esbuild), tests (node
# --test: the TextMate grammar, snippets, configuration), vsce package.
# Needs node >= 20 and npm, and the npm registry (or a warm npm cache).
set -euo pipefail
cd "$(dirname "$0")"

npm ci --no-audit --no-fund
npm run compile
npm test
rm -f mcl.vsix
npx vsce package --no-dependencies --allow-missing-repository --out mcl.vsix

# The package holds the bundle and every declarative contribution.
test -s mcl.vsix
node - <<'JS'
const fs = require('fs');
const zip = fs.readFileSync('mcl.vsix');
const names = [];
// Walk the zip's central directory.
const eocd = zip.lastIndexOf(Buffer.from([0x50, 0x4b, 0x05, 0x06]));
let p = zip.readUInt32LE(eocd + 16);
for (let i = 0, n = zip.readUInt16LE(eocd + 10); i < n; i++) {
  const len = zip.readUInt16LE(p + 28), extra = zip.readUInt16LE(p + 30), comment = zip.readUInt16LE(p + 32);
  names.push(zip.toString('utf8', p + 46, p + 46 + len));
  p += 46 + len + extra + comment;
}
const want = [
  'extension/package.json',
  'extension/out/extension.js',
  'extension/syntaxes/mcl.tmLanguage.json',
  'extension/language-configuration.json',
  'extension/snippets/mcl.json',
];
const missing = want.filter((w) => !names.includes(w));
if (missing.length) {
  console.error('mcl.vsix lacks ' + missing.join(', ') + '; it holds:\n' + names.join('\n'));
  process.exit(1);
}
if (names.some((n) => n.includes('node_modules/') || n.startsWith('extension/src/'))) {
  console.error('mcl.vsix holds sources or node_modules:\n' + names.join('\n'));
  process.exit(1);
}
console.log(`mcl.vsix: ${names.length} files, ${zip.length} bytes`);
JS
