// The bundle that VS Code loads (out/extension.js, made by `npm run bundle`)
// loads with every dependency inside it, and exports activate/deactivate.
// `vscode` is the only module it may require; a stub stands in for it.

'use strict';

const test = require('node:test');
const assert = require('node:assert');
const fs = require('node:fs');
const path = require('node:path');
const Module = require('node:module');

const bundle = path.join(__dirname, '..', 'out', 'extension.js');

/** Any property of the stub is another stub, callable, constructible, extensible. */
function stub() {
  const f = function () {
    return stub();
  };
  return new Proxy(f, {
    get(target, prop) {
      if (prop === 'prototype' || prop in target) {
        return target[prop];
      }
      return typeof prop === 'symbol' ? undefined : stub();
    },
    construct() {
      return stub();
    },
  });
}

test('the bundle loads and exports activate and deactivate', { skip: !fs.existsSync(bundle) && 'run `npm run bundle` first' }, () => {
  const required = [];
  const load = Module._load;
  Module._load = function (request, parent, isMain) {
    if (parent && parent.filename === bundle) {
      required.push(request);
    }
    if (request === 'vscode') {
      return stub();
    }
    return load.call(this, request, parent, isMain);
  };
  try {
    const ext = require(bundle);
    assert.strictEqual(typeof ext.activate, 'function');
    assert.strictEqual(typeof ext.deactivate, 'function');
  } finally {
    Module._load = load;
  }
  const external = required.filter((r) => r !== 'vscode' && !r.startsWith('node:') && !Module.builtinModules.includes(r));
  assert.deepStrictEqual(external, [], 'the bundle requires modules that the .vsix does not hold');
});
