// The playground's page: the editor, its diagnostics, the parameter sliders, the
// derivation, and the report of the run (the page `lagrange report` writes, made by the
// same library function, shown in an iframe). All computing happens in worker.js; a call
// still running when the model changes is abandoned by restarting the worker.
//
// For the browser tests, `window.lagrange.call(call, source, options)` answers with the
// parsed result and the worker's time, and `document.body.dataset.state` is `ready` once
// the page shows the current text's result (`error` when that is a diagnostic).

const $ = (id) => document.getElementById(id);
const source = $('source');
const backdrop = $('backdrop');
const diagnostic = $('diagnostic');
const status = $('status');
const DEBOUNCE_MS = 250;

// ---------------------------------------------------------------------------------------
// The worker and its calls.

let worker = null;
let nextId = 0;
const pending = new Map();

function startWorker() {
  worker = new Worker(new URL('./worker.js', import.meta.url), { type: 'module' });
  worker.onmessage = (event) => {
    const { id, result, ms } = event.data;
    const resolve = pending.get(id);
    pending.delete(id);
    if (resolve) resolve({ value: JSON.parse(result), ms });
  };
  worker.onerror = (event) => {
    status.textContent = `worker error: ${event.message}`;
  };
}

/** Calls the library in the worker: {value (the parsed JSON), ms}. */
function call(name, text, options = {}) {
  const id = nextId++;
  return new Promise((resolve) => {
    pending.set(id, resolve);
    worker.postMessage({ id, call: name, source: text, options });
  });
}

/** Abandons every call in flight (a long run of an old text): a fresh worker. */
function restartWorker() {
  worker.terminate();
  for (const resolve of pending.values()) resolve(null);
  pending.clear();
  startWorker();
}

startWorker();
window.lagrange = { call };

// ---------------------------------------------------------------------------------------
// Examples: examples.json, written by build.sh from examples/.

let examples = { models: [], files: {} };
let folder = '';
// The example last chosen: its folder resolves the files the text names, edited or not.
let chosen = '';
// The menu's neutral entry, shown once the text is no longer the chosen example's.
const EDITED = '';

async function loadExamples() {
  examples = await (await fetch('examples.json')).json();
  const menu = $('examples');
  const edited = document.createElement('option');
  Object.assign(edited, { value: EDITED, textContent: '(edited)', disabled: true, hidden: true });
  menu.append(edited);
  for (const m of examples.models) {
    const option = document.createElement('option');
    option.value = m.path;
    option.textContent = m.path.replace(/\.toml$/, '');
    menu.append(option);
  }
  menu.addEventListener('change', () => choose(menu.value));
}

function choose(path) {
  chosen = path;
  $('examples').value = path;
  folder = path.includes('/') ? path.slice(0, path.lastIndexOf('/')) : '';
  source.value = examples.files[path];
  parameterValues = {};
  parameterNames = ''; // the sliders are made again at the file's values
  changed();
}

/** The menu names the example while the text is that example's, and says "(edited)" after. */
function markEdited() {
  $('examples').value = source.value === examples.files[chosen] ? chosen : EDITED;
}

// ---------------------------------------------------------------------------------------
// The editor's underline: the backdrop holds the same text, with the error's range marked.

function escapeHtml(text) {
  return text.replace(/&/g, '&amp;').replace(/</g, '&lt;').replace(/>/g, '&gt;');
}

function underline(error) {
  const text = source.value;
  if (!error || error.start === undefined || error.file) {
    backdrop.innerHTML = escapeHtml(text) + '\n';
    return;
  }
  // The first line of the range; an empty one marks a space where it starts.
  const start = Math.min(error.start, text.length);
  let end = Math.min(Math.max(error.end, start), text.length);
  const newline = text.indexOf('\n', start);
  if (newline !== -1 && newline < end) end = newline;
  const inside = text.slice(start, end);
  backdrop.innerHTML =
    escapeHtml(text.slice(0, start)) +
    `<mark data-line="${error.line}" data-column="${error.column}">${inside ? escapeHtml(inside) : ' '}</mark>` +
    escapeHtml(text.slice(end)) + '\n';
}

source.addEventListener('scroll', () => {
  backdrop.scrollTop = source.scrollTop;
  backdrop.scrollLeft = source.scrollLeft;
});

function showError(error) {
  underline(error);
  const where = error.line ? `${error.file ? error.file + ':' : ''}line ${error.line}, column ${error.column}: ` : '';
  diagnostic.textContent = where + error.message + (error.inner ? `: ${error.inner}` : '') +
    (error.help ? `\nhelp: ${error.help}` : '');
  diagnostic.hidden = false;
}

function clearError() {
  underline(null);
  diagnostic.hidden = true;
  diagnostic.textContent = '';
}

// ---------------------------------------------------------------------------------------
// Parameters as sliders: from 0 to twice the file's value (or ±1 about 0), each with a
// number box beside it that takes an exact value (the slider moves in 200 steps; a
// value typed outside its range widens it).

let parameterValues = {};
let parameterNames = '';

function sliders(parameters) {
  const names = parameters.map((p) => p.name).join(',');
  if (names === parameterNames) return;
  parameterNames = names;
  const box = $('parameters');
  box.replaceChildren();
  for (const p of parameters) {
    const value = parameterValues[p.name] ?? p.value;
    const [lo, hi] = p.value === 0 ? [-1, 1] : p.value > 0 ? [0, 2 * p.value] : [2 * p.value, 0];
    const label = document.createElement('label');
    label.textContent = p.name;
    label.htmlFor = `parameter-${p.name}`;
    const slider = document.createElement('input');
    Object.assign(slider, { type: 'range', id: `parameter-${p.name}`, min: lo, max: hi, step: (hi - lo) / 200, value });
    slider.dataset.name = p.name;
    const exact = document.createElement('input');
    Object.assign(exact, { type: 'number', id: `value-${p.name}`, step: 'any', value: String(value) });
    exact.dataset.name = p.name;
    exact.setAttribute('aria-label', `${p.name} (exact value)`);
    slider.addEventListener('input', () => {
      parameterValues[p.name] = Number(slider.value);
      exact.value = slider.value;
      schedule(runOnly);
    });
    exact.addEventListener('input', () => {
      const v = exact.valueAsNumber;
      if (!Number.isFinite(v)) return;
      parameterValues[p.name] = v;
      if (v < Number(slider.min)) slider.min = v;
      if (v > Number(slider.max)) slider.max = v;
      slider.value = v;
      schedule(runOnly);
    });
    box.append(label, slider, exact);
  }
}

// ---------------------------------------------------------------------------------------
// Updating: model (diagnostics, sliders) → derive (typeset) → report (the run).

let generation = 0;
let timer = null;

function schedule(work) {
  clearTimeout(timer);
  timer = setTimeout(work, DEBOUNCE_MS);
}

function options() {
  const until = Number($('until').value);
  return { set: { ...parameterValues }, until: until > 0 ? until : 10, samples: 1001, files: examples.files, folder };
}

function changed() {
  schedule(update);
}

async function update() {
  const mine = ++generation;
  if (pending.size) restartWorker();
  document.body.dataset.state = 'busy';
  status.textContent = 'deriving…';
  const text = source.value;
  const parsed = await call('model', text, { files: examples.files, folder });
  if (!parsed || mine !== generation) return;
  if (parsed.value.format === 'lagrange.error/1') {
    showError(parsed.value);
    status.textContent = 'the model has an error';
    document.body.dataset.state = 'error';
    return;
  }
  clearError();
  for (const name of Object.keys(parameterValues)) {
    if (!parsed.value.parameters.some((p) => p.name === name)) delete parameterValues[name];
  }
  sliders(parsed.value.parameters);
  const derived = await call('derive', text, options());
  if (!derived || mine !== generation) return;
  if (derived.value.format === 'lagrange.error/1') {
    showError(derived.value);
    status.textContent = 'the model has an error';
    document.body.dataset.state = 'error';
    return;
  }
  $('equations').innerHTML = derived.value.mathml;
  await run(mine, text, derived.ms);
}

async function runOnly() {
  const mine = ++generation;
  if (pending.size) restartWorker();
  document.body.dataset.state = 'busy';
  await run(mine, source.value, 0);
}

async function run(mine, text, deriveMs) {
  status.textContent = 'running…';
  const ran = await call('report', text, options());
  if (!ran || mine !== generation) return;
  if (ran.value.format === 'lagrange.error/1') {
    showError(ran.value);
    status.textContent = 'the run could not start';
    document.body.dataset.state = 'error';
    return;
  }
  $('report').srcdoc = ran.value.page;
  const steps = ran.value.summary?.steps;
  status.textContent = `derived in ${deriveMs.toFixed(0)} ms, derived and ran${steps ? ` ${steps} steps` : ''} in ${ran.ms.toFixed(0)} ms (WebAssembly)`;
  document.body.dataset.state = 'ready';
}

source.addEventListener('input', () => {
  underline(null);
  markEdited();
  changed();
});
$('until').addEventListener('change', () => schedule(runOnly));

loadExamples().then(() => {
  const first = examples.models.find((m) => m.path === 'double_pendulum.toml') || examples.models[0];
  choose(first.path);
});
