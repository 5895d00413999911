// The playground's worker: loads the library (lagrange_web.wasm, through the JS glue that
// wasm-bindgen generated) and answers calls, so that a long run never blocks the page.
// A message {id, call, source, options} is answered with {id, result, ms}: `result` is the
// JSON text the library returned, `ms` the time the call took in this worker.

import init, * as lagrange from './pkg/lagrange_web.js';

const CALLS = ['model', 'derive', 'simulate', 'report', 'modes', 'orbit', 'top', 'extremal'];
const ready = init({ module_or_path: new URL('./pkg/lagrange_web_bg.wasm', import.meta.url) });

self.onmessage = async (event) => {
  const { id, call, source, options } = event.data;
  try {
    await ready;
    if (!CALLS.includes(call)) throw new Error(`no such call: ${call}`);
    const start = performance.now();
    const result = lagrange[call](source, JSON.stringify(options || {}));
    self.postMessage({ id, result, ms: performance.now() - start });
  } catch (error) {
    const result = JSON.stringify({ format: 'lagrange.error/1', message: `internal error: ${error}` });
    self.postMessage({ id, result, ms: 0 });
  }
};
