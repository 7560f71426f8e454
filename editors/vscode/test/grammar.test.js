// The TextMate grammar tokenizes the example models as intended:
// `npm test` in editors/vscode (after `npm install`).
const test = require('node:test');
const assert = require('node:assert');
const fs = require('node:fs');
const path = require('node:path');
const oniguruma = require('vscode-oniguruma');
const { Registry, INITIAL, parseRawGrammar } = require('vscode-textmate');

const wasm = fs.readFileSync(require.resolve('vscode-oniguruma/release/onig.wasm')).buffer;
const onigLib = oniguruma.loadWASM(wasm).then(() => ({
  createOnigScanner: (p) => new oniguruma.OnigScanner(p),
  createOnigString: (s) => new oniguruma.OnigString(s),
}));
const registry = new Registry({
  onigLib,
  loadGrammar: async () => {
    const file = path.join(__dirname, '..', 'syntaxes', 'som.tmLanguage.json');
    return parseRawGrammar(fs.readFileSync(file, 'utf8'), file);
  },
});

/** Every token of `text` as [text, innermost scope]. */
async function tokens(text) {
  const grammar = await registry.loadGrammar('source.som');
  let state = INITIAL;
  const out = [];
  for (const line of text.split('\n')) {
    const r = grammar.tokenizeLine(line, state);
    for (const t of r.tokens) {
      const s = line.slice(t.startIndex, t.endIndex);
      if (s.trim()) out.push([s.trim(), t.scopes[t.scopes.length - 1]]);
    }
    state = r.ruleStack;
  }
  return out;
}

function scopeOf(found, text) {
  const hit = found.find(([s]) => s === text);
  return hit ? hit[1] : undefined;
}

test('the ship: keywords, names, numbers, comments', async () => {
  const ship = fs.readFileSync(path.join(__dirname, '..', '..', '..', 'examples', 'models', 'ship.som'), 'utf8');
  const found = await tokens(ship);
  assert.strictEqual(scopeOf(found, 'model'), 'keyword.other.model.som');
  assert.strictEqual(scopeOf(found, 'Ship'), 'entity.name.type.model.som');
  assert.strictEqual(scopeOf(found, 'disturbance'), 'keyword.other.som');
  assert.strictEqual(scopeOf(found, 'unmeasured'), 'storage.modifier.som');
  assert.strictEqual(scopeOf(found, 'der'), 'keyword.other.equation.som');
  assert.strictEqual(scopeOf(found, '1.0'), 'constant.numeric.som');
  // `water.u`: the medium and the state apart (a bare `water` is a plain name).
  assert.ok(found.some(([s, scope]) => s === 'water' && scope === 'variable.other.medium.som'));
  assert.ok(found.some(([s, scope]) => s === 'u' && scope === 'variable.other.state.som'));
  assert.ok(found.some(([s, scope]) => s.startsWith('sample time') && scope === 'comment.line.double-slash.som'));
});

test('data blocks: strings and units; a block comment over lines', async () => {
  const found = await tokens('data { psi = "heading" in deg/s }\n/* a\n b */ step 0.1');
  assert.strictEqual(scopeOf(found, 'heading'), 'string.quoted.double.som');
  assert.strictEqual(scopeOf(found, 'deg/s'), 'support.constant.unit.som');
  assert.strictEqual(scopeOf(found, 'b'), 'comment.block.som');
  assert.strictEqual(scopeOf(found, 'step'), 'keyword.other.som');
});
