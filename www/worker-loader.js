// A computation worker's loader: every worker of the lab starts from this file — the first by
// index.html as the page is read, the others by the page's pool (src/web/components/pool.rs).
//
// Its first message is the worker's module: compiled (a WebAssembly.Module, handed on by the
// page), or its address, which this worker then fetches and compiles itself, off the page's
// thread, and posts back as { kind: 'module', module } for the page's other workers. The worker's
// own script (cutlab-worker.js, src/bin/cutlab-worker.rs) then instantiates the module and posts
// { kind: 'ready' }. A module that cannot be loaded is thrown as the worker's error, which the
// page reports, rather than leaving it to wait for a `ready` that will not come.
'use strict';

/** The module at `address`, compiled as its bytes arrive (or from all of them, for a server that
 * does not send wasm as application/wasm). */
function compile(address) {
  return WebAssembly.compileStreaming(fetch(address)).catch(function () {
    return fetch(address).then(function (response) {
      if (!response.ok) throw new Error('the worker module ' + address + ': HTTP ' + response.status);
      return response.arrayBuffer();
    }).then(function (bytes) {
      return WebAssembly.compile(bytes);
    });
  });
}

self.onmessage = function (event) {
  self.onmessage = null;
  var given = event.data;
  var module = given instanceof WebAssembly.Module
    ? Promise.resolve(given)
    : compile(given).then(function (compiled) {
      self.postMessage({ kind: 'module', module: compiled });
      return compiled;
    });
  // Fetched while the module compiles.
  importScripts('cutlab-worker.js');
  module.then(function (compiled) {
    return wasm_bindgen({ module_or_path: compiled });
  }).catch(function (error) {
    setTimeout(function () { throw error; });
  });
};
