// Tests of the declarative parts of the extension, with Node's test runner
// (`npm test`): the TextMate grammar tokenizes MCL as expected (through
// vscode-textmate and the Oniguruma engine VS Code uses), and every file that
// package.json names exists and is valid.

'use strict';

const test = require('node:test');
const assert = require('node:assert');
const fs = require('node:fs');
const path = require('node:path');
const vsctm = require('vscode-textmate');
const oniguruma = require('vscode-oniguruma');

const root = path.join(__dirname, '..');
const examples = path.join(root, '..', '..', 'examples');

async function loadGrammar() {
  const wasm = fs.readFileSync(require.resolve('vscode-oniguruma/release/onig.wasm')).buffer;
  await oniguruma.loadWASM(wasm);
  const registry = new vsctm.Registry({
    onigLib: Promise.resolve({
      createOnigScanner: (patterns) => new oniguruma.OnigScanner(patterns),
      createOnigString: (s) => new oniguruma.OnigString(s),
    }),
    loadGrammar: async (scopeName) => {
      if (scopeName !== 'source.mcl') return null;
      const file = path.join(root, 'syntaxes', 'mcl.tmLanguage.json');
      return vsctm.parseRawGrammar(fs.readFileSync(file, 'utf8'), file);
    },
  });
  return registry.loadGrammar('source.mcl');
}

/** Tokenizes `text`; returns [{ text, scopes }] for every token of every line. */
function tokenize(grammar, text) {
  let state = vsctm.INITIAL;
  const out = [];
  for (const line of text.split('\n')) {
    const r = grammar.tokenizeLine(line, state);
    for (const t of r.tokens) {
      out.push({ text: line.slice(t.startIndex, t.endIndex), scopes: t.scopes });
    }
    state = r.ruleStack;
  }
  return out;
}

/** Asserts that some token with exactly `text` has a scope starting with `scope`. */
function expectScope(tokens, text, scope) {
  const found = tokens.filter((t) => t.text === text);
  assert.ok(found.length > 0, `no token \`${text}\``);
  assert.ok(
    found.some((t) => t.scopes.some((s) => s.startsWith(scope))),
    `\`${text}\` has scopes ${JSON.stringify(found.map((t) => t.scopes))}, expected ${scope}`,
  );
}

test('the grammar scopes every construct', async () => {
  const grammar = await loadGrammar();
  const src = [
    'import "vehicle.mcl"; // a comment',
    'actions { enableGoto = GotoPrimitive( c: enable, v: way-point ); }',
    'pattern { P_X : dir/file.xml; T { places { begin.1; off(1); } transitions { TO(timeout); } arcs { begin.1 -> TT0; a → b; } } }',
    'tasks { Goto( way-point ): AchieveOneGoal { a: enableGoto -> T0; e: eventGotoOk -> T2; } }',
    'mission : auv [ x at 3 ] {',
    '    /* block',
    '       comment */',
    '    if ( Alarm() ) { Goto( [24, -12.5] ) : first } else { Trajectory( v, path[[0, 0]] ) } ;',
    '    while ( not ( Done() ) ) { parallel { A() } or { B() } and { C() } } ;',
    '    monitor { try { A() } catch { B() } } while_condition ( S( "cable \\"x\\"" ) ) do { C() }',
    '}',
    'mcl_plan_op GotoOp( x, y ) { Goto( [x, y] ) }',
    'constraints { _mutex_ { sonar, auv:usbl } = 1 order { asc:a, auv:b } }',
    'planning { operator move( vehicle v ) { precond { v in l1; } expression { l1 != l2; } } }',
  ].join('\n');
  const tokens = tokenize(grammar, src);
  expectScope(tokens, 'import', 'keyword.control.import');
  expectScope(tokens, 'vehicle.mcl', 'string.quoted.double');
  expectScope(tokens, ' a comment', 'comment.line');
  expectScope(tokens, 'enableGoto', 'entity.name.function.action');
  expectScope(tokens, 'GotoPrimitive', 'entity.name.type.primitive');
  expectScope(tokens, 'c', 'keyword.other.marker');
  expectScope(tokens, 'way-point', 'variable');
  expectScope(tokens, 'P_X', 'entity.name.type.pattern');
  expectScope(tokens, 'dir/file.xml', 'string.unquoted.path');
  expectScope(tokens, 'places', 'storage.type.block');
  expectScope(tokens, '->', 'keyword.operator.arrow');
  expectScope(tokens, '→', 'keyword.operator.arrow');
  expectScope(tokens, 'Goto', 'entity.name.function');
  expectScope(tokens, 'AchieveOneGoal', 'entity.name.type.pattern');
  expectScope(tokens, 'mission', 'storage.type');
  expectScope(tokens, 'auv', 'entity.name.namespace');
  expectScope(tokens, 'at', 'keyword.other.at');
  expectScope(tokens, '       comment ', 'comment.block');
  expectScope(tokens, 'if', 'keyword.control.conditional');
  expectScope(tokens, 'else', 'keyword.control.conditional');
  expectScope(tokens, 'Alarm', 'entity.name.function');
  expectScope(tokens, '-12.5', 'constant.numeric');
  expectScope(tokens, 'first', 'entity.name.label');
  expectScope(tokens, 'path', 'entity.name.type.tag');
  expectScope(tokens, 'planning', 'storage.type.block');
  expectScope(tokens, 'operator', 'storage.type.planning');
  expectScope(tokens, 'precond', 'keyword.other.planning');
  expectScope(tokens, '!=', 'keyword.operator.comparison');
  expectScope(tokens, 'while', 'keyword.control.loop');
  expectScope(tokens, 'while_condition', 'keyword.control.loop');
  expectScope(tokens, 'not', 'keyword.operator.logical');
  expectScope(tokens, 'or', 'keyword.operator.logical');
  expectScope(tokens, 'parallel', 'keyword.control');
  expectScope(tokens, 'try', 'keyword.control.exception');
  expectScope(tokens, '\\"', 'constant.character.escape');
  expectScope(tokens, 'GotoOp', 'entity.name.function.mission');
  expectScope(tokens, 'x', 'variable.parameter');
  expectScope(tokens, '_mutex_', 'keyword.other.constraint');
  expectScope(tokens, 'order', 'keyword.other.constraint');
  expectScope(tokens, 'sonar', 'entity.name.label');
  expectScope(tokens, 'usbl', 'entity.name.label');
});

test('identifiers with dashes and slashes are one token; arrows and comments end them', async () => {
  const grammar = await loadGrammar();
  const tokens = tokenize(grammar, 'arcs { begin->TT0; a-b/c -> d; x//note\n}');
  expectScope(tokens, 'begin', 'variable');
  expectScope(tokens, '->', 'keyword.operator.arrow');
  expectScope(tokens, 'a-b/c', 'variable');
  expectScope(tokens, 'x', 'variable');
  expectScope(tokens, 'note', 'comment.line');
});

test('every example tokenizes, and no keyword inside a name is highlighted', async () => {
  const grammar = await loadGrammar();
  const files = fs.readdirSync(examples).filter((f) => f.endsWith('.mcl'));
  assert.ok(files.length >= 8);
  for (const f of files) {
    const tokens = tokenize(grammar, fs.readFileSync(path.join(examples, f), 'utf8'));
    assert.ok(tokens.length > 0, f);
    for (const t of tokens) {
      if (t.scopes.some((s) => s.startsWith('keyword.control') || s.startsWith('storage.type'))) {
        assert.match(
          t.text,
          /^(import|actions|events|patterns?|tasks|mission|mcl_plan_op|constraints|places|transitions|arcs|if|then|else|while_condition|while|do|try|catch|parallel|monitor|condition)$/,
          `${f}: \`${t.text}\` scoped ${t.scopes.join(' ')}`,
        );
      }
    }
  }
});

test('package.json names files that exist and are valid', () => {
  const pkg = JSON.parse(fs.readFileSync(path.join(root, 'package.json'), 'utf8'));
  assert.deepStrictEqual(pkg.contributes.languages[0].extensions, ['.mcl']);
  assert.ok(pkg.activationEvents.includes('onLanguage:mcl'));
  assert.strictEqual(pkg.contributes.configuration.properties['mcl.server.path'].default, 'mcl');
  const files = [
    pkg.contributes.languages[0].configuration,
    pkg.contributes.grammars[0].path,
    pkg.contributes.snippets[0].path,
  ];
  for (const f of files) {
    JSON.parse(fs.readFileSync(path.join(root, f), 'utf8'));
  }
  const conf = JSON.parse(fs.readFileSync(path.join(root, pkg.contributes.languages[0].configuration), 'utf8'));
  assert.deepStrictEqual(conf.comments, { lineComment: '//', blockComment: ['/*', '*/'] });
  const word = new RegExp(conf.wordPattern);
  assert.strictEqual('way-point->x'.match(word)[0], 'way-point');
  assert.strictEqual('sonar/front//c'.match(word)[0], 'sonar/front');
  new RegExp(conf.folding.markers.start);
  new RegExp(conf.indentationRules.increaseIndentPattern);
  assert.ok(new RegExp(conf.indentationRules.increaseIndentPattern).test('    if ( A() ) {'));
  assert.ok(new RegExp(conf.indentationRules.decreaseIndentPattern).test('    } else {'));
});

test('every control structure has a snippet, and every snippet is well formed', () => {
  const snippets = JSON.parse(fs.readFileSync(path.join(root, 'snippets', 'mcl.json'), 'utf8'));
  const prefixes = Object.values(snippets).map((s) => s.prefix);
  for (const p of ['mission', 'if', 'ifelse', 'while', 'try', 'parallel', 'parallelor', 'monitor', 'monitorwhile', 'not', 'constraints', 'tasks', 'pattern', 'actions', 'events']) {
    assert.ok(prefixes.includes(p), `no snippet \`${p}\``);
  }
  for (const [name, s] of Object.entries(snippets)) {
    const body = s.body.join('\n');
    assert.ok(s.description, name);
    // Balanced placeholders: every `${` closes.
    let depth = 0;
    for (let i = 0; i < body.length; i++) {
      if (body[i] === '\\') {
        i++;
      } else if (body.startsWith('${', i)) {
        depth++;
        i++;
      } else if (body[i] === '}' && depth > 0) {
        depth--;
      }
    }
    assert.strictEqual(depth, 0, `${name}: unbalanced placeholder`);
  }
});
